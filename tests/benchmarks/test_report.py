"""BENCHMARKS.md's assembly from the benchmarks' fragments (`benchmarks.report`)."""

from __future__ import annotations

import datetime

from benchmarks import report


def test_benchmarks_md_collects_the_fragments_and_relinks_plots(tmp_path):
    out = tmp_path / "docs" / "bench"
    out.mkdir(parents=True)
    (out / "summary.md").write_text("ratio 0.3\n\n![engine](engine.png)\n")
    (out / "stress.md").write_text("0 NaN\n")
    text = report.compose(out, tmp_path, date=datetime.date(2026, 11, 22), command="python -m benchmarks.report")
    assert "Assembled 2026-11-22" in text and "`python -m benchmarks.report`" in text
    assert "![engine](docs/bench/engine.png)" in text
    assert text.index("## Run time against error") < text.index("## Numerical stress")
    assert "Not in this run: skip.md, quality.md, defaults_fidelity.md, defaults_fidelity_shared.md, defaults_ab.md, plugins.md, shearwarp_peers.md, occlusion_bound.md, resampling_floor.md, app.md, first_preview.md, zarr_levels.md, scale.md, oneshot.md, gpu.md." in text
