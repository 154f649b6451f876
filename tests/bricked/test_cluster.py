"""Sort-last rendering on a dask.distributed LocalCluster of worker processes (issue 24): equal to
one process's render, completing when a worker dies mid-frame, and one-line errors for a
scheduler that cannot be reached and for bad --cluster values."""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import pytest

from volren.api import prepared_renderer
from volren.bricked.cluster import ClusterRenderer, VolumeSpec, ZarrSpec, connect, local_client, parse_cluster
from volren.errors import VolrenError
from volren.io import ome_zarr_io
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.renderers.registry import registry
from volren.testing.silent_server import silent_server

pytest.importorskip("distributed", reason="dask.distributed is part of the test set-up")

TF = TransferFunction1D(
    [[0, 0.1, 0.4, 1.0], [2, 0.9, 0.9, 0.2], [4, 1.0, 0.2, 0.1]],
    [[0, 0.0], [1.0, 0.1], [2.5, 0.5], [4, 0.2]],
    2.0,
)


def field_volume() -> UniformVolume:
    z, y, x = np.meshgrid(np.arange(21), np.arange(18), np.arange(25), indexing="ij")
    values = 2 + 1.5 * np.sin(0.35 * x) * np.cos(0.3 * y) + 0.03 * z
    return UniformVolume(values.astype(np.float32), (1.0, 1.2, 0.9), (0.0, 1.0, -2.0), name="field")


@pytest.fixture(scope="module")
def client():
    client = local_client(2)
    yield client
    cluster = client.cluster
    client.close()
    cluster.close()


def whole_render(name, volume, settings, camera, size=(24, 20)):
    with prepared_renderer(name, volume, TF, settings) as renderer:
        return renderer.render(camera, *size)


def rmse(a, b):
    return float(np.sqrt(np.mean((a.astype(np.float64) - b) ** 2)))


def test_two_workers_draw_what_one_process_draws(client):
    volume = field_volume()
    settings = RenderSettings(shade=True)
    camera = Camera.orbit(volume.bounds, 40, 25, zoom=1.2)
    expected = whole_render("reference", volume, settings, camera)
    renderer = ClusterRenderer(client, VolumeSpec(volume), "reference", brick=6)
    calls: list[float] = []
    try:
        image, frame = renderer.render(settings, TF, camera, 24, 20, calls.append)
        again, _ = renderer.render(settings, TF, camera.azimuth(90), 24, 20)  # another view, the same workers
    finally:
        renderer.close()
    assert expected[..., 3].max() > 0.2 and rmse(image, expected) <= 1e-5
    assert rmse(again, whole_render("reference", volume, settings, camera.azimuth(90))) <= 1e-5
    assert frame.workers == 2 and len(frame.worker_ms) == 2  # both workers drew
    assert frame.runs >= 2 and frame.drawn == frame.bricks
    assert calls == sorted(calls) and calls[-1] == 1.0 and len(calls) == frame.runs


@pytest.mark.usefixtures("opengl")
def test_workers_stream_an_ome_zarr_level_with_the_slicer(client, tmp_path):
    volume = UniformVolume((field_volume().values * 1000).astype(np.uint16), (1.0, 1.2, 0.9), name="field")
    path = tmp_path / "field.zarr"
    ome_zarr_io.save_ome_zarr(volume, path, chunk=8, levels=2)
    tf = TransferFunction1D(
        [[0, 0.1, 0.4, 1.0], [4000, 1.0, 0.2, 0.1]], [[0, 0.0], [1000, 0.1], [4000, 0.4]], 2.0
    )
    settings = RenderSettings(preintegration=True, options={"early_termination": False})
    camera = Camera.orbit(volume.bounds, -30, 15)
    whole = ome_zarr_io.load_level(path, 0)
    renderer = registry.create("slicer")
    try:
        renderer.set_settings(settings)
        renderer.set_volume(whole)
        renderer.set_transfer_function(tf)
        expected = renderer.render(camera, 24, 20)
    finally:
        renderer.release()
    cluster_renderer = ClusterRenderer(client, ZarrSpec(str(path), 0, 1 << 20), "slicer", brick=8)
    try:
        image, frame = cluster_renderer.render(settings, tf, camera, 24, 20)
    finally:
        cluster_renderer.close()
    assert rmse(image, expected) <= 1e-5 and frame.drawn > 4


@dataclass(frozen=True)
class DiesOnce(VolumeSpec):
    """A volume whose first opening on a worker, while `marker` exists, kills that worker."""

    marker: str = ""

    def __getstate__(self) -> dict:
        return {**super().__getstate__(), "marker": self.marker}

    def __setstate__(self, state: dict) -> None:
        super().__setstate__(state)
        object.__setattr__(self, "marker", state["marker"])

    def open(self, data=None):
        if self.marker and os.path.exists(self.marker) and data is not None:
            try:
                os.unlink(self.marker)
            except FileNotFoundError:
                pass
            else:
                os._exit(1)
        return super().open(data)


def test_a_worker_lost_mid_frame_has_its_bricks_rerun_elsewhere(client, tmp_path):
    volume = field_volume()
    settings = RenderSettings()
    camera = Camera.orbit(volume.bounds, 15, 35)
    marker = tmp_path / "die"
    renderer = ClusterRenderer(client, DiesOnce(volume, marker=str(marker)), "reference", brick=6)
    try:
        marker.write_text("the first worker to open the volume exits")
        image, frame = renderer.render(settings, TF, camera, 24, 20)
    finally:
        renderer.close()
    assert not marker.exists()  # a worker did die
    assert rmse(image, whole_render("reference", volume, settings, camera)) <= 1e-5
    assert frame.drawn == frame.bricks


def test_a_frame_after_every_worker_restarted_sends_the_volume_again(client):
    """The scattered volume lives only on the workers: when they are all replaced (a restart, or every
    worker that held it lost), the next frame scatters it again and draws, instead of failing."""
    volume = field_volume()
    settings = RenderSettings()
    camera = Camera.orbit(volume.bounds, 15, 35)
    renderer = ClusterRenderer(client, VolumeSpec(volume), "reference", brick=6)
    try:
        client.restart()
        image, frame = renderer.render(settings, TF, camera, 24, 20)
    finally:
        renderer.close()
    assert rmse(image, whole_render("reference", volume, settings, camera)) <= 1e-5
    assert frame.drawn == frame.bricks


def test_volren_render_from_python_on_a_local_cluster():
    import volren

    volume = field_volume()
    flags = {"renderer": "reference", "size": (16, 12), "elevation": 30}
    assert rmse(volren.render(volume, cluster="local:2", **flags), volren.render(volume, **flags)) <= 1e-5


def test_a_scheduler_that_cannot_be_reached_is_one_line():
    """A closed port and a port where something says nothing (no dask greeting) are one line each,
    naming the time limit given (how long giving up takes: `python -m benchmarks.give_up_times`)."""
    with pytest.raises(
        VolrenError, match=r"cannot reach the dask scheduler at tcp://127.0.0.1:9 within 2 s"
    ) as exc:
        connect("tcp://127.0.0.1:9", timeout=2.0)
    assert "\n" not in str(exc.value)
    with (
        silent_server() as port,
        pytest.raises(VolrenError, match=rf"at tcp://127.0.0.1:{port} within 0.5 s") as exc,
    ):
        connect(f"tcp://127.0.0.1:{port}", timeout=0.5)
    assert "\n" not in str(exc.value)


def test_cluster_flags_are_checked():
    assert parse_cluster("local:3") == 3 and parse_cluster("local") >= 1
    for bad, message in (
        ("remote", "takes local or local:N"),
        ("local:0", "N in 1..256"),
        ("local:x", "N in 1..256"),
    ):
        with pytest.raises(VolrenError, match=message):
            parse_cluster(bad)


@pytest.mark.slow  # starts a local dask cluster: about 13 s
@pytest.mark.filterwarnings("default::volren.errors.VolrenWarning")
def test_volren_render_on_a_local_cluster_equals_one_process(tmp_path, capsys):
    from volren.cli.main import main

    volume = UniformVolume((field_volume().values * 1000).astype(np.uint16), (1.0, 1.2, 0.9), name="field")
    path = tmp_path / "field.zarr"
    ome_zarr_io.save_ome_zarr(volume, path, chunk=8, levels=2)
    flags = ["--renderer", "reference", "--size", "20x16", "--level", "0"]
    assert (
        main(["render", str(path), *flags, "--cluster", "local:2", "--save-array", str(tmp_path / "c.npy")])
        == 0
    )
    line = capsys.readouterr().out
    assert "(field.zarr level 0 on 2 workers:" in line and "bricks drawn in" in line
    assert main(["render", str(path), *flags, "--save-array", str(tmp_path / "w.npy")]) == 0
    assert rmse(np.load(tmp_path / "c.npy"), np.load(tmp_path / "w.npy")) <= 1e-5
    capsys.readouterr()
    assert (
        main(["render", str(path), *flags, "--scheduler", "tcp://127.0.0.1:9", "-o", str(tmp_path / "x.png")])
        == 1
    )
    assert "cannot reach the dask scheduler at tcp://127.0.0.1:9" in capsys.readouterr().err


class _Listener:
    """A TCP port on 127.0.0.1 where something other than a dask scheduler listens: it accepts,
    sends `reply` (nothing: it says nothing at all) and keeps the connection open until closed."""

    def __init__(self, reply: bytes) -> None:
        import socket
        import threading

        self.reply, self.held = reply, []
        self.server = socket.socket()
        self.server.bind(("127.0.0.1", 0))
        self.server.listen(8)
        self.server.settimeout(0.2)
        self.address = f"tcp://127.0.0.1:{self.server.getsockname()[1]}"
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while not self.stop.is_set():
            try:
                connection = self.server.accept()[0]
            except OSError:
                continue
            self.held.append(connection)
            if self.reply:
                connection.sendall(self.reply)

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)
        for connection in self.held:
            connection.close()
        self.server.close()


def render_in_a_thread(argv: list[str], limit: float) -> tuple[bool, int | None]:
    """`volren ARGV` in a thread: (whether it ended within `limit` s, its status)."""
    import threading

    from volren.cli.main import main

    status: list[int] = []
    thread = threading.Thread(target=lambda: status.append(main(argv)), daemon=True)
    thread.start()
    thread.join(limit)
    return not thread.is_alive(), status[0] if status else None


@pytest.mark.parametrize("reply", [b"", b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n", b"\0" * 64],
                         ids=["silent", "http", "zeros"])  # fmt: skip
def test_a_port_where_no_scheduler_listens_is_one_line_within_the_time_limit(
    tmp_path, capsys, monkeypatch, reply
):
    """Something else listening (a web server, a service that says nothing, bytes that are not dask's):
    the greeting is bounded by the connection time limit, and the error names --scheduler."""
    from volren.bricked import cluster
    from volren.io import save_volume

    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 1.0)
    save_volume(field_volume(), tmp_path / "field.vti")
    listener = _Listener(reply)
    try:
        argv = ["render", str(tmp_path / "field.vti"), "--size", "12", "--scheduler", listener.address,
                "-o", str(tmp_path / "x.png")]  # fmt: skip
        ended, status = render_in_a_thread(argv, limit=20)
    finally:
        listener.close()
    assert ended and status == 1
    reason = "no answer" if not reply else "what answered is not a dask scheduler"
    assert capsys.readouterr().err.splitlines() == [
        f"volren: error: --scheduler: cannot reach the dask scheduler at {listener.address} within 1 s ({reason})"
    ]


@pytest.mark.parametrize(("flags", "message"), [
    (["--cluster", ""], "--cluster takes local or local:N (N worker processes), got ''; for a running cluster give "
                        "--scheduler ADDRESS"),
    (["--scheduler", ""], "--scheduler needs the ADDRESS of a running dask scheduler (e.g. tcp://host:8786), got ''"),
    (["--scheduler", "tls://127.0.0.1:9"], "--scheduler tls://127.0.0.1:9: a TLS scheduler needs the client's "
     "certificate in dask's configuration (distributed.comm.tls.ca-file, .client.cert and .client.key)"),
    (["--cluster", "local:1", "--renderer", "vtk"], "renderer vtk does not draw bricks, which a cluster (--cluster, "
     "--scheduler) needs; these do: reference, slicer"),
])  # fmt: skip
def test_cluster_flags_that_cannot_apply_are_refused_naming_them(tmp_path, capsys, flags, message):
    """An empty --cluster or --scheduler rendered here without a word, TLS without certificates
    was an internal error, and a renderer that draws no bricks was refused only once the cluster's
    workers had started, naming neither flag."""
    from volren.cli.main import main
    from volren.io import save_volume

    save_volume(field_volume(), tmp_path / "field.vti")
    argv = ["render", str(tmp_path / "field.vti"), "--size", "12", *flags, "-o", str(tmp_path / "x.png")]
    assert main(argv) == 1
    assert capsys.readouterr().err.splitlines() == [f"volren: error: {message}"]
    assert not (tmp_path / "x.png").exists()


def test_an_empty_cluster_or_scheduler_from_python_is_refused_not_ignored():
    import volren

    for where, message in (({"cluster": ""}, "--cluster takes local or local:N"),
                           ({"scheduler": ""}, "--scheduler needs the ADDRESS")):  # fmt: skip
        with pytest.raises(VolrenError, match=message):
            volren.render(field_volume(), renderer="reference", size=(8, 8), **where)
