"""`volren convert` and `volren movie` given bad inputs, outputs and flags, and the flags of
`volren render` that choose a cluster (--cluster, --scheduler) or how an OME-Zarr image is read
(--memory, --level), given values they must refuse or that do not apply.

Every case is small: the inputs are the 8x7x6 grid seed (`v.vti`) and the OME-Zarr seed
(`img.zarr`), images and movies 16x16, movies 2 frames. No case starts a cluster: an unreachable
scheduler is asked with the connection timeout patched to `SCHEDULER_TIMEOUT_S`.
"""

from __future__ import annotations

from collections.abc import Iterator

from benchmarks.fuzz.cases import BAD_NUMBERS, Case, Expect
from benchmarks.fuzz.json_cases import _volume_files
from benchmarks.fuzz.output_cases import SIDE, VOLUME, spot_case, spots
from benchmarks.fuzz.seeds import seeds
from benchmarks.fuzz.zarr_cases import IMAGE
from benchmarks.fuzz.zarr_cases import seed_files as zarr_files

CONVERT = "convert"
MOVIE = "movie"
FLAGS = "cluster-memory-flags"
#: Seconds a case waits for a scheduler that is not there (the command waits 10).
SCHEDULER_TIMEOUT_S = 0.5
#: A port on this machine where no dask scheduler listens (the discard service's, if anything).
NO_SCHEDULER = "tcp://127.0.0.1:9"


# ------------------------------------------------------------------------------------ convert


def _convert(what: str, files: dict[str, bytes], argv: tuple[str, ...], expect: Expect = "error",
             names: tuple[str, ...] = (), **more) -> Case:  # fmt: skip
    return Case(f"{CONVERT}/{what}", CONVERT, files, ("convert", *argv), expect, names, array=None, **more)


def convert_cases(volume: dict[str, bytes], image: dict[str, bytes]) -> Iterator[Case]:
    """Inputs that are not volumes, outputs over, inside and holding the input (with and without
    --force), a headerless raw file with and without the --raw-* flags, outputs not named *.zarr,
    bad --chunks, --levels."""
    zattrs = f"{IMAGE}/.zattrs"
    yield _convert(
        "valid", volume, (VOLUME, "out.zarr"), "render", after=(("written", "out.zarr"), ("kept", VOLUME))
    )
    yield _convert(
        "valid-from-ome-zarr",
        image,
        (IMAGE, "out.zarr"),
        "any",
        after=(("written", "out.zarr"), ("kept", zattrs)),
    )
    yield _convert("missing-input", {}, ("nowhere.vti", "out.zarr"), names=("nowhere.vti",))
    yield _convert(
        "input-empty-folder", {}, ("empty", "out.zarr"), names=("empty",), nodes=(("folder", "empty"),)
    )
    yield _convert("input-folder-of-text", {"notes/a.txt": b"text"}, ("notes", "out.zarr"), names=("notes",))
    yield _convert(
        "input-fifo", {}, ("pipe.vti", "out.zarr"), names=("pipe.vti",), nodes=(("fifo", "pipe.vti"),)
    )
    yield _convert(
        "input-socket", {}, ("sock.vti", "out.zarr"), names=("sock.vti",), nodes=(("socket", "sock.vti"),)
    )
    mesh = next(s for s in seeds() if s.name == "vtu-binary")
    yield _convert("input-mesh", dict(mesh.files), (mesh.target, "out.zarr"), names=(mesh.target,))
    for force in ((), ("--force",)):
        tag = "-force" if force else ""
        yield _convert(
            f"output-is-the-input{tag}",
            image,
            (IMAGE, IMAGE, *force),
            names=(IMAGE,),
            after=(("kept", zattrs),),
        )
        holder = {f"out.zarr/{VOLUME}": volume[VOLUME]}
        yield _convert(
            f"output-holds-the-input{tag}",
            holder,
            (f"out.zarr/{VOLUME}", "out.zarr", *force),
            names=("out.zarr",),
            after=(("kept", f"out.zarr/{VOLUME}"),),
        )
        yield _convert(
            f"output-inside-the-input{tag}",
            image,
            (IMAGE, f"{IMAGE}/inner.zarr", *force),
            "any",
            names=(IMAGE,),
            after=(("kept", zattrs),),
        )
        yield _convert(
            f"output-exists{tag}",
            {**volume, "out.zarr/.zgroup": b"{}"},
            (VOLUME, "out.zarr", *force),
            "any" if force else "error",
            names=("out.zarr",),
            after=(("kept", VOLUME),),
        )
    raw = next(s for s in seeds() if s.name == "raw")
    yield _convert("raw-without-shape", dict(raw.files), (raw.target, "out.zarr"), names=(raw.target,))
    yield _convert(
        "raw-flags",
        dict(raw.files),
        (raw.target, "out.zarr", *raw.flags),
        "render",
        after=(("written", "out.zarr"), ("kept", raw.target)),
    )  # convert takes render's --raw-* flags
    for output in ("out.vti", "out", ".zarr", "out.zarr.zip"):
        yield _convert(
            f"output-named-{output}", volume, (VOLUME, output), names=(output,), after=(("kept", VOLUME),)
        )
    yield _convert(
        "output-named-OUT.ZARR", volume, (VOLUME, "OUT.ZARR"), "any", after=(("written", "OUT.ZARR"),)
    )
    for flag, value in (("--chunks", "0"), ("--chunks", "-4"), ("--chunks", "abc"), ("--levels", "0"),
                        ("--levels", "1.5"), ("--scalars", "nosuch"), ("--scalars", "")):  # fmt: skip
        yield _convert(
            f"flag{flag}={value or 'empty'}", volume, (VOLUME, "out.zarr", flag, value), names=(flag, VOLUME)
        )
    for flag, value in (("--chunks", "99999999999"), ("--levels", "99")):
        yield _convert(
            f"flag{flag}={value}", volume, (VOLUME, "out.zarr", flag, value), "any", names=(flag, VOLUME)
        )
    for spot in spots("out.zarr"):
        yield spot_case(f"{CONVERT}/output={spot.label}", CONVERT, spot, ("convert", VOLUME, spot.path), "OUTPUT",
                        None, volume)  # fmt: skip


def convert_sweep(volume: dict[str, bytes]) -> Iterator[Case]:
    """Every seed converted (the grids convert, the rest are refused), and --chunks and --levels
    given every bad number."""
    for seed in seeds():
        yield _convert(f"sweep-seed-{seed.name}", dict(seed.files), (seed.target, "out.zarr"), "any",
                       names=(seed.target,), after=(("written", "out.zarr"),))  # fmt: skip
    for flag in ("--chunks", "--levels"):
        for value in BAD_NUMBERS:
            yield _convert(f"sweep{flag}={value or 'empty'}", volume, (VOLUME, "out.zarr", flag, value),
                           "error" if value != "4294967296" else "any", names=(flag,))  # fmt: skip


# -------------------------------------------------------------------------------------- movie


def movie_argv(output: str = "out.gif", *extra: str) -> tuple[str, ...]:
    """A 2-frame 16x16 movie of the grid seed into `output`, plus `extra` flags (which may repeat
    --frames: the last one counts)."""
    return ("movie", VOLUME, "-o", output, "--frames", "2", "--size", SIDE, *extra)


def _movie(what: str, volume: dict[str, bytes], argv: tuple[str, ...], expect: Expect, names: tuple[str, ...],
           output: str = "out.gif") -> Case:  # fmt: skip
    return Case(f"{MOVIE}/{what}", MOVIE, volume, argv, expect, names, after=(("written", output), ("kept", VOLUME)),
                array=None)  # fmt: skip


def movie_cases(volume: dict[str, bytes]) -> Iterator[Case]:
    """--fps and --frames out of range, -o at every place and with suffixes movies do not have."""
    yield _movie("valid", volume, movie_argv(), "render", ())
    for fps in ("0", "-1", "1e-300", "1e-6", "0.001", "nan", "inf", "-inf", "241", "1e308", "abc", ""):
        yield _movie(
            f"fps={fps or 'empty'}", volume, movie_argv("out.gif", "--fps", fps), "error", ("--fps",)
        )
    for fps in ("51", "240"):  # GIF frames shorter than 2 hundredths of a second play as 10
        yield _movie(f"fps={fps}", volume, movie_argv("out.gif", "--fps", fps), "error", ("--fps", "out.gif"))
    for fps, output in (("0.01", "out.gif"), ("50", "out.gif"), ("240", "out.mp4")):  # the ends of the ranges
        yield _movie(
            f"fps={fps}-{output}", volume, movie_argv(output, "--fps", fps), "any", ("--fps",), output
        )
    for frames in ("0", "-1", "100001", "99999999999", "1.5", "abc"):
        yield _movie(
            f"frames={frames}", volume, movie_argv("out.gif", "--frames", frames), "error", ("--frames",)
        )
    for output in ("out.avi", "out", "out.gif.txt"):
        yield _movie(f"o-named-{output}", volume, movie_argv(output), "error", ("-o", output), output)
    yield _movie("o-named-OUT.GIF", volume, movie_argv("OUT.GIF"), "any", ("-o",), "OUT.GIF")
    yield _movie("no-o", volume, ("movie", VOLUME, "--frames", "2", "--size", SIDE), "error", ("-o",))
    yield _movie("lossless-gif", volume, movie_argv("out.gif", "--lossless"), "error", ("--lossless",))
    for spot in spots("out.gif"):
        yield spot_case(f"{MOVIE}/o={spot.label}", MOVIE, spot, movie_argv(spot.path), "-o", None, volume)


def movie_sweep(volume: dict[str, bytes]) -> Iterator[Case]:
    """--fps, --frames and --orbit given every bad number."""
    for flag in ("--fps", "--frames", "--orbit"):
        for value in BAD_NUMBERS:
            angle = flag == "--orbit" and value not in ("nan", "inf", "-inf", "abc", "", "1,5")
            expect: Expect = "any" if angle else "error"
            yield _movie(
                f"sweep{flag}={value or 'empty'}", volume, movie_argv("out.gif", flag, value), expect, (flag,)
            )


# ----------------------------------------------------------------------- cluster and memory flags


def _flags(what: str, files: dict[str, bytes], target: str, flags: tuple[str, ...], expect: Expect = "error",
           **more) -> Case:  # fmt: skip
    argv = ("render", target, "-o", "out.png", "--save-array", "out.npy", "--size", SIDE, *flags)
    names = tuple(f for f in flags if f.startswith("--")) + (target,)
    return Case(f"{FLAGS}/{what}", FLAGS, files, argv, expect, names, **more)


#: --cluster values that name no cluster; none starts one (local, or local: with no N, would).
CLUSTER_VALUES = ("", "local:0", "local:-1", "local:abc", "local:257", "local:1.5", "remote", "local:1:2")
#: --scheduler values where no scheduler answers, each refused within `SCHEDULER_TIMEOUT_S`.
SCHEDULER_VALUES = ("", NO_SCHEDULER, "tls://127.0.0.1:9", " ", "nosuch://127.0.0.1:9", "tcp://127.0.0.1:99999",
                    "tcp://", "127.0.0.1")  # fmt: skip
_SHORT_WAIT = (("volren.bricked.cluster", "CONNECT_TIMEOUT_S", SCHEDULER_TIMEOUT_S),)


def _scheduler(what: str, value: str) -> str:
    return f"{what}={value.strip() or ('blank' if value else 'empty')}"


def flag_cases(volume: dict[str, bytes], image: dict[str, bytes]) -> Iterator[Case]:
    """--cluster and --scheduler values that name no cluster, --memory and --level out of range on
    an OME-Zarr image, and both given for inputs they do not apply to."""
    for value in CLUSTER_VALUES:
        yield _flags(f"cluster={value or 'empty'}", volume, VOLUME, ("--cluster", value))
    for value in SCHEDULER_VALUES[:3]:
        yield _flags(
            _scheduler("scheduler", value), volume, VOLUME, ("--scheduler", value), patches=_SHORT_WAIT
        )
    yield _flags(
        "cluster-and-scheduler", volume, VOLUME, ("--cluster", "local:1", "--scheduler", NO_SCHEDULER)
    )
    for value in ("0", "1", "-5", "lots", "5XB", "nan", "inf", "", "1e-3"):
        yield _flags(f"memory={value or 'empty'}", image, IMAGE, ("--memory", value))
    yield _flags(
        "memory=1e30", image, IMAGE, ("--memory", "1e30", "--renderer", "raycast"), "any"
    )  # no GL: quick
    for value in ("-1", "99", "2", "abc", "1.5", ""):
        yield _flags(f"level={value or 'empty'}", image, IMAGE, ("--level", value))
    for flags in (("--memory", "2GB"), ("--memory", "lots"), ("--level", "0"), ("--level", "99")):
        yield _flags(f"{VOLUME}{flags[0]}={flags[1]}", volume, VOLUME, flags)
    raw = next(s for s in seeds() if s.name == "raw")
    yield _flags("raw-memory", dict(raw.files), raw.target, (*raw.flags, "--memory", "2GB"))


def flag_sweep(volume: dict[str, bytes], image: dict[str, bytes]) -> Iterator[Case]:
    """--memory and --level on the OME-Zarr image and --cluster local:N given every bad number;
    the other unreachable schedulers, and --cluster and --scheduler with the OME-Zarr image."""
    for value in BAD_NUMBERS:
        label = value or "empty"
        memory_expect: Expect = "any" if value in ("1e308", "4294967296", "99999999999999999999") else "error"
        yield _flags(f"sweep-memory={label}", image, IMAGE, ("--memory", value), memory_expect)
        yield _flags(
            f"sweep-level={label}", image, IMAGE, ("--level", value), "any" if value == "0" else "error"
        )
        if value:  # local: is local, which would start a cluster of every core
            yield _flags(f"sweep-cluster=local:{label}", volume, VOLUME, ("--cluster", f"local:{value}"))
    for value in SCHEDULER_VALUES[3:]:
        yield _flags(
            _scheduler("sweep-scheduler", value), volume, VOLUME, ("--scheduler", value), patches=_SHORT_WAIT
        )
    for value in CLUSTER_VALUES:
        yield _flags(f"sweep-{IMAGE}-cluster={value or 'empty'}", image, IMAGE, ("--cluster", value))
    for value in SCHEDULER_VALUES[:3]:
        yield _flags(_scheduler(f"sweep-{IMAGE}-scheduler", value), image, IMAGE, ("--scheduler", value),
                     patches=_SHORT_WAIT)  # fmt: skip


# ----------------------------------------------------------------------------------- together


def command_cases() -> list[Case]:
    """Every convert, movie, and cluster and memory flag case, in a fixed order."""
    volume, image = _volume_files(), zarr_files()
    return [*convert_cases(volume, image), *movie_cases(volume), *flag_cases(volume, image),
            *convert_sweep(volume), *movie_sweep(volume), *flag_sweep(volume, image)]  # fmt: skip
