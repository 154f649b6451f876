"""`python -m benchmarks.fastest_peer`: a row per scene naming VTK's quickest setting at our error,
on a bundled sample at a small size."""

from __future__ import annotations

from benchmarks import fastest_peer


def test_no_options_against_vtks_fastest_at_our_error(capsys, tmp_path, renders_with_vtk):
    out = tmp_path / "peer.md"
    argv = ["--datasets", "marschner_lobb", "--size", "24", "--frames", "2", "--out", str(out)]
    assert fastest_peer.main(argv) == 0
    (line,) = [x for x in capsys.readouterr().out.splitlines() if x.startswith("| marschner_lobb/sample |")]
    row = [c.strip() for c in line.strip("|").split("|")]
    ours_ms, our_rmse, peer, peer_ms, peer_rmse = (
        float(row[2]),
        float(row[3]),
        row[4],
        float(row[5]),
        float(row[6]),
    )
    assert ours_ms > 0 and peer_ms > 0 and 0 < our_rmse < 0.1
    assert peer.split()[0] in ("fixed_point", "gpu")
    # the peer reaches our error, or the row says that none does
    assert peer_rmse <= our_rmse or "none reaches ours" in peer
    assert abs(float(row[7].rstrip("x")) - peer_ms / ours_ms) <= 0.01 * peer_ms / ours_ms + 0.01
    assert line in out.read_text()
