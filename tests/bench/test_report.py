"""BENCHMARKS.md's assembly from the benchmarks' fragments (`benchmarks.report`)."""

from __future__ import annotations

import datetime

from benchmarks import report


def test_benchmarks_md_collects_the_fragments_and_relinks_plots(tmp_path):
    out = tmp_path / "docs" / "bench"
    out.mkdir(parents=True)
    (out / "summary.md").write_text("ratio 0.3\n\n![engine](engine.png)\n")
    (out / "stress.md").write_text("0 NaN\n")
    text = report.compose(
        out, tmp_path, date=datetime.date(2026, 11, 22), command="python -m benchmarks.report"
    )
    assert "Assembled 2026-11-22" in text and "`python -m benchmarks.report`" in text
    assert "![engine](docs/bench/engine.png)" in text
    assert text.index("## Run time against error") < text.index("## Numerical stress")
    assert (
        "Not in this run: skip.md, quality.md, defaults_fidelity.md, defaults_fidelity_shared.md, defaults_ab.md, fastest_peer.md, viewer_peers.md, plugins.md, shearwarp_peers.md, occlusion_bound.md, resampling_floor.md, clipping.md, tf2d.md, tf2d_drag.md, app.md, app_latency.md, first_preview.md, zarr_levels.md, scale.md, oneshot.md, step_search.md, packet_probe.md, native_march.md, tetra_walk.md, labels.md, channels.md, gpu.md."
        in text
    )


def test_fragment_headings_nest_under_their_section(tmp_path, monkeypatch):
    """A fragment written as a page of its own (an H1 title, H2 parts) must not give BENCHMARKS.md
    a second title: its headings move below the section's, code blocks left alone."""
    monkeypatch.setattr(report, "machine", lambda: "a test machine")  # no GL context for the header
    out = tmp_path / "bench"
    out.mkdir()
    (out / "summary.md").write_text(
        "# Run time against error\n\nratio\n\n## bonsai\n\n```sh\n# a comment\n```\n"
    )
    (out / "plugins.md").write_text("### Speed at equal error\n\n1.5x\n")
    text = report.compose(out, tmp_path, date=datetime.date(2026, 11, 22))
    headings = [line for line in text.splitlines() if line.startswith("#")]
    assert headings == [
        "# Benchmarks",
        "## Run time against error",
        "### Run time against error",
        "#### bonsai",
        "# a comment",  # inside the code block
        "## The plugin renderers (shear-warp, object order)",
        "### Speed at equal error",
    ]
