"""A corpus prepared off-line: force maps, reliefs and normals for every picture of a folder, on Dask.

    import hapticfield.batch as hb
    report = hb.run("pictures/", [hb.force_map(), hb.relief(mm_per_level=0.02)], "out/")

Every input gets one file per job in the output folder, named after the input's path under the folder (or its
file name, for a list of paths) and the job: `out/cat.png.force_map.npy`. The files are numpy's .npy
(`numpy.load` reads them): a force map is H x W x 2 float32 (fx, fy: the tangible-image force, 1 at a black/white
edge, fy down the picture; hapticfield.force_map), a relief H x W float64 heights [m] and normals H x W x 3
float64 unit normals (x right, y up the picture, z toward the user; hapticfield.relief_map), row 0 the
picture's top row.

Where the work runs (`scheduler=`): None, a Dask LocalCluster of `workers` workers on this machine; an address
("tcp://host:8786") or a distributed.Client, a cluster already running (every worker needs hapticfield
installed); "serial", a plain loop in this process. Every path writes the same bytes: each output is computed
by the same function and written to a temporary file in the output folder, then renamed, so an output that
exists is complete, a killed run leaves none half written, and a second run skips what the first finished.
A picture that cannot be read (missing, corrupt, too small) is reported in Report.failed and the rest of the
corpus goes on.

    python3 -m hapticfield.batch --help
"""
from __future__ import annotations

import argparse
import ast
import dataclasses
import importlib
import os
import pathlib
import sys
import time
import uuid
from typing import IO, Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy
import numpy.typing

import hapticfield as _hf

_npy: Any = numpy.lib.format  # the .npy format: numpy.save's own writer, and the header readers

__all__ = ["Job", "Failure", "Report", "force_map", "relief", "normals", "corpus", "run", "main"]

#: The pictures a folder is searched for when no pattern is given (what OpenCV reads).
PICTURES = ("*.png", "*.jpg", "*.jpeg", "*.bmp", "*.tif", "*.tiff", "*.webp", "*.pgm", "*.ppm", "*.pnm", "*.pbm")
#: The products a Job makes, and the library call each one comes from.
PRODUCTS = ("force_map", "relief", "normals")

Paths = Union[str, "os.PathLike[str]", Iterable[Union[str, "os.PathLike[str]"]]]
Options = Tuple[Tuple[str, Any], ...]


@dataclasses.dataclass(frozen=True)
class Job:
    """One product made for every input: `product` (force_map, relief or normals), the options of the library
    call that makes it, and `name`, the output's suffix (`INPUT.NAME.npy`; the product unless given)."""

    product: str
    options: Options = ()
    name: str = ""

    def __post_init__(self) -> None:
        if self.product not in PRODUCTS:
            raise ValueError(f"job: unknown product '{self.product}' (choose {', '.join(PRODUCTS)})")
        if not self.name:
            object.__setattr__(self, "name", self.product)
        if not self.name.replace("_", "").replace("-", "").isalnum():
            raise ValueError(f"job: the name '{self.name}' must be letters, digits, '_' and '-' only")

    def compute(self, image: Union[str, numpy.typing.ArrayLike]) -> numpy.typing.NDArray[Any]:
        """This job's array for one picture (a path or an array, as the library calls take them)."""
        return self._pick(self._call(image))

    def _source(self) -> Tuple[str, Options]:
        """The library call behind the product: relief and normals with the same options share one."""
        return ("force_map" if self.product == "force_map" else "relief_map", self.options)

    def _call(self, image: Any) -> Tuple[numpy.typing.NDArray[Any], numpy.typing.NDArray[Any]]:
        if self.product == "force_map":
            fx, fy = _hf.force_map(image, **dict(self.options))
            return fx, fy
        heights, normal = _hf.relief_map(image, **dict(self.options))
        return heights, normal

    def _pick(self, arrays: Tuple[numpy.typing.NDArray[Any], numpy.typing.NDArray[Any]]) -> numpy.typing.NDArray[Any]:
        if self.product == "force_map":
            return numpy.stack(arrays, axis=-1)
        return arrays[0] if self.product == "relief" else arrays[1]


def _job(product: str, name: str, **options: Any) -> Job:
    job = Job(product, tuple(sorted(options.items())), name)
    # Settings are checked once, here, on a blank picture larger than any mask (129 px): a bad mask is one
    # error, not one per file.
    job.compute(numpy.zeros((160, 160), dtype=numpy.uint8))
    return job


def force_map(mask: str = "prewitt", size: Optional[int] = None, border: str = "suspend", sigma: float = 0.0,
              gray: str = "paper", name: str = "force_map") -> Job:
    """The tangible-image force at every pixel (hapticfield.force_map): H x W x 2 float32 (fx, fy)."""
    return _job("force_map", name, mask=mask, size=size, border=border, sigma=sigma, gray=gray)


def relief(pixel_size: float = 1e-4, mm_per_level: float = 0.01, blur: float = 0.0, dark_is_high: bool = False,
           gray: str = "paper", name: str = "relief") -> Job:
    """The picture's relief (hapticfield.relief_map): H x W float64 heights [m]."""
    return _job("relief", name, pixel_size=pixel_size, mm_per_level=mm_per_level, blur=blur,
                dark_is_high=dark_is_high, gray=gray)


def normals(pixel_size: float = 1e-4, mm_per_level: float = 0.01, blur: float = 0.0, dark_is_high: bool = False,
            gray: str = "paper", name: str = "normals") -> Job:
    """The relief's normals (hapticfield.relief_map): H x W x 3 float64, unit."""
    return _job("normals", name, pixel_size=pixel_size, mm_per_level=mm_per_level, blur=blur,
                dark_is_high=dark_is_high, gray=gray)


@dataclasses.dataclass(frozen=True)
class Failure:
    """An output that could not be made: the input, the job's name and why (the exception, in one line)."""

    input: pathlib.Path
    job: str
    message: str

    def __str__(self) -> str:
        return f"{self.input}: {self.job}: {self.message}"


@dataclasses.dataclass
class Report:
    """What a run did: outputs written and skipped (complete from an earlier run), failures, inputs, seconds."""

    written: List[pathlib.Path] = dataclasses.field(default_factory=list)
    skipped: List[pathlib.Path] = dataclasses.field(default_factory=list)
    failed: List[Failure] = dataclasses.field(default_factory=list)
    inputs: int = 0
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        """True when every output exists."""
        return not self.failed

    def __str__(self) -> str:
        return (f"{self.inputs} input{'' if self.inputs == 1 else 's'}: {len(self.written)} outputs written, {len(self.skipped)} skipped, "
                f"{len(self.failed)} failed in {self.seconds:.2f} s")


def corpus(inputs: Paths, pattern: Optional[str] = None) -> List[Tuple[pathlib.Path, str]]:
    """The inputs as (path, name) pairs, sorted: a folder's files matching `pattern` (a glob under it, e.g.
    "**/*.png" for every level; the usual picture extensions when None), named by their path under the folder;
    or a list of files, named by their file names (two of one name raise ValueError). A missing folder (or
    single file) raises FileNotFoundError; a missing file in a list fails alone, in run()'s report."""
    if isinstance(inputs, (str, os.PathLike)):
        root = pathlib.Path(inputs)
        if not root.exists():
            raise FileNotFoundError(f"inputs: no such folder or file: {root}")
        if root.is_dir():
            found = {p for g in ([pattern] if pattern else PICTURES) for p in root.glob(g) if p.is_file()}
            if pattern is None:  # the extensions in capitals too (IMG_0001.JPG)
                found |= {p for g in PICTURES for p in root.glob(g.upper()) if p.is_file()}
            return sorted((p, p.relative_to(root).as_posix()) for p in found)
        inputs = [root]
    pairs: Dict[str, pathlib.Path] = {}
    for item in inputs:
        path = pathlib.Path(item)
        if path.is_dir():
            raise ValueError(f"inputs: {path} is a folder; give one folder, or a list of files")
        if path.name in pairs:
            raise ValueError(f"inputs: {pairs[path.name]} and {path} would write the same outputs (one file name)")
        pairs[path.name] = path
    return sorted((p, n) for n, p in pairs.items())


def _complete(path: pathlib.Path) -> bool:
    """An .npy file whose header parses and whose size is its header's plus its data's."""
    try:
        with open(path, "rb") as f:
            version = _npy.read_magic(f)
            if version == (1, 0):
                shape, _, dtype = _npy.read_array_header_1_0(f)
            elif version == (2, 0):
                shape, _, dtype = _npy.read_array_header_2_0(f)
            else:
                return False
            data = int(numpy.prod(shape, dtype=numpy.int64)) * numpy.dtype(dtype).itemsize
            return f.tell() + data == os.fstat(f.fileno()).st_size
    except (OSError, ValueError):
        return False


def _write(array: numpy.typing.NDArray[Any], out: pathlib.Path) -> None:
    """numpy.save's bytes into a hidden temporary file beside `out`, then renamed onto it."""
    out.parent.mkdir(parents=True, exist_ok=True)
    part = out.with_name(f".{out.name}.{uuid.uuid4().hex}.part")
    try:
        with open(part, "wb") as f:
            _npy.write_array(f, numpy.ascontiguousarray(array), allow_pickle=False)
            f.flush()
            os.fsync(f.fileno())
        os.replace(part, out)
    except BaseException:
        part.unlink(missing_ok=True)
        raise


def make(path: str, jobs: Sequence[Job], outputs: Sequence[str]) -> List[Tuple[str, Optional[str]]]:
    """One input's outputs, what a worker runs: (output, None) for each written, (output, why) for each failed."""
    done: List[Tuple[str, Optional[str]]] = []
    made: Dict[Tuple[str, Options], Tuple[numpy.typing.NDArray[Any], numpy.typing.NDArray[Any]]] = {}
    for job, out in zip(jobs, outputs):
        try:
            source = job._source()
            if source not in made:
                made[source] = job._call(path)
            _write(job._pick(made[source]), pathlib.Path(out))
            done.append((out, None))
        except Exception as e:  # a bad picture is reported, and the corpus goes on
            done.append((out, f"{type(e).__name__}: {' '.join(str(e).split())}"))
    return done


class _Progress:
    """`batch: 12/40 inputs, 1 failed` on one line of `stream`, redrawn at most every 0.2 s and at the end."""

    def __init__(self, total: int, stream: Optional[IO[str]]) -> None:
        self.total, self.stream, self.done, self.failed, self.shown = total, stream, 0, 0, 0.0

    def step(self, failed: int) -> None:
        self.done += 1
        self.failed += failed
        now = time.monotonic()
        if self.stream is not None and (now - self.shown >= 0.2 or self.done == self.total):
            self.shown = now
            end = "\n" if self.done == self.total else ""
            self.stream.write(f"\rbatch: {self.done}/{self.total} inputs, {self.failed} failed{end}")
            self.stream.flush()


def _distributed() -> Any:
    try:
        return importlib.import_module("distributed")
    except ImportError:
        raise RuntimeError("scheduler: Dask's distributed is not installed (Debian: python3-distributed); "
                           "scheduler='serial' runs without it") from None


def run(inputs: Paths, jobs: Union[Job, Sequence[Job]], out: Union[str, "os.PathLike[str]"], *,
        pattern: Optional[str] = None, scheduler: Any = None, workers: int = 2, threads_per_worker: int = 1,
        processes: bool = False, progress: Union[bool, IO[str]] = True) -> Report:
    """Makes every job's output for every input (see corpus()) in the folder `out`, skipping the outputs that
    are there and complete, and returns a Report; a failed input does not stop the others.

    scheduler: None (a LocalCluster of `workers` workers, `threads_per_worker` threads each, in threads of this
    process, or in processes of their own with processes=True), "serial" (a plain loop here), a scheduler's
    address or a distributed.Client. progress: True (a line on stderr), False, or a stream to write it to."""
    job_list = [jobs] if isinstance(jobs, Job) else list(jobs)
    if not job_list or not all(isinstance(j, Job) for j in job_list):
        raise ValueError("jobs: give one or more Job (batch.force_map(), batch.relief(), batch.normals())")
    names = [j.name for j in job_list]
    if len(set(names)) != len(names):
        raise ValueError(f"jobs: two jobs write the same outputs ({names}); give them different name=")
    if workers < 1 or threads_per_worker < 1:
        raise ValueError("workers and threads_per_worker must be >= 1")
    if scheduler is not None and not isinstance(scheduler, str) and not isinstance(scheduler, _distributed().Client):
        raise ValueError(f"scheduler: expected None, 'serial', an address or a distributed.Client, got {scheduler!r}")
    start = time.monotonic()
    out_dir = pathlib.Path(out)
    report = Report()
    tasks: List[Tuple[pathlib.Path, List[Job], List[str]]] = []
    for path, name in corpus(inputs, pattern):
        report.inputs += 1
        todo: List[Job] = []
        outputs: List[str] = []
        for job in job_list:
            target = out_dir / f"{name}.{job.name}.npy"
            for stale in target.parent.glob(f".{target.name}.*.part"):  # left by a run that was killed
                stale.unlink(missing_ok=True)
            if _complete(target):
                report.skipped.append(target)
                continue
            todo.append(job)
            outputs.append(str(target))
        if todo:
            tasks.append((path, todo, outputs))
    stream: Optional[IO[str]] = None
    if isinstance(progress, bool):
        stream = sys.stderr if progress else None
    else:
        stream = progress
    bar = _Progress(len(tasks), stream)

    def collect(path: pathlib.Path, done: List[Tuple[str, Optional[str]]]) -> None:
        failures = 0
        for target, why in done:
            if why is None:
                report.written.append(pathlib.Path(target))
            else:
                report.failed.append(Failure(path, pathlib.Path(target).name.rsplit(".", 2)[-2], why))
                failures += 1
        bar.step(failures)

    if scheduler == "serial" or not tasks:
        for path, todo, outputs in tasks:
            collect(path, make(str(path), todo, outputs))
    else:
        distributed = _distributed()
        if scheduler is None:
            with distributed.LocalCluster(n_workers=workers, threads_per_worker=threads_per_worker,
                                          processes=processes, dashboard_address=None) as cluster:
                with distributed.Client(cluster) as client:
                    _submit_all(client, distributed, tasks, collect)
        elif isinstance(scheduler, str):
            with distributed.Client(scheduler) as client:
                _submit_all(client, distributed, tasks, collect)
        else:
            _submit_all(scheduler, distributed, tasks, collect)
    report.written.sort()
    report.failed.sort(key=lambda f: (str(f.input), f.job))
    report.seconds = time.monotonic() - start
    return report


def _submit_all(client: Any, distributed: Any, tasks: List[Tuple[pathlib.Path, List[Job], List[str]]],
                collect: Any) -> None:
    """One task per input; results collected as they finish. A task that fails as a whole (its worker died)
    fails each of its outputs."""
    futures = {client.submit(make, str(path), todo, outputs, pure=False): (path, todo, outputs)
               for path, todo, outputs in tasks}
    for future in distributed.as_completed(futures):
        path, todo, outputs = futures[future]
        try:
            done = future.result()
        except Exception as e:
            done = [(o, f"{type(e).__name__}: {' '.join(str(e).split())}") for o in outputs]
        collect(path, done)
        future.release()


USAGE = """usage: python3 -m hapticfield.batch INPUT... --out DIR [options]
Makes force maps, reliefs and normals for a corpus of pictures, on Dask.
  INPUT                 one folder (its pictures, see --pattern) or one or more picture files
  --out DIR             the output folder: INPUT.JOB.npy for each input and job
  --job JOB[:K=V,...]   force_map (default), relief or normals, with the options of
                        hapticfield.batch.force_map() / relief() / normals(), e.g.
                        relief:mm_per_level=0.02,blur=1; repeat for several
  --pattern GLOB        the folder's files to take, e.g. '**/*.png' (default: the usual
                        picture extensions, top level only)
  --scheduler S         serial (a plain loop), or a Dask scheduler's address
                        (default: a local cluster of --workers workers)
  --workers N           local cluster workers (default 2)
  --threads N           threads per worker (default 1)
  --processes           local workers in processes of their own (default: threads)
  --quiet               no progress line
  -h, --help            this text
Outputs already there and complete are skipped; each failed input is one line on stderr.
Exit status: 0 done, 1 an input failed or bad input, 2 usage error.
"""


class _Usage(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> Any:  # one line, not argparse's usage block
        raise _Usage(message)


def _job_argument(text: str) -> Job:
    product, _, rest = text.partition(":")
    options: Dict[str, Any] = {}
    for item in filter(None, rest.split(",")):
        key, sep, value = item.partition("=")
        if not sep:
            raise _Usage(f"--job {text}: options are KEY=VALUE, got '{item}'")
        try:
            options[key.strip()] = ast.literal_eval(value.strip())
        except (ValueError, SyntaxError):
            options[key.strip()] = value.strip()  # a word: a mask, a border, a gray
    factories: Dict[str, Callable[..., Job]] = {"force_map": force_map, "relief": relief, "normals": normals}
    if product not in factories:
        raise _Usage(f"--job: unknown product '{product}' (choose {', '.join(PRODUCTS)})")
    try:
        return factories[product](**options)
    except TypeError as e:
        raise _Usage(f"--job {text}: {e}") from None


def main(argv: Optional[Sequence[str]] = None) -> int:
    """The command line (USAGE); returns the exit status."""
    args_list = list(sys.argv[1:] if argv is None else argv)
    if "-h" in args_list or "--help" in args_list:
        sys.stdout.write(USAGE)
        return 0
    parser = _Parser(add_help=False)
    parser.add_argument("inputs", nargs="+")
    parser.add_argument("--out", required=True)
    parser.add_argument("--job", action="append", default=[])
    parser.add_argument("--pattern")
    parser.add_argument("--scheduler")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--processes", action="store_true")
    parser.add_argument("--quiet", action="store_true")
    try:
        args = parser.parse_args(args_list)
        jobs = [_job_argument(j) for j in args.job] or [force_map()]
        inputs: Paths = args.inputs[0] if len(args.inputs) == 1 else args.inputs
        report = run(inputs, jobs, args.out, pattern=args.pattern, scheduler=args.scheduler, workers=args.workers,
                     threads_per_worker=args.threads, processes=args.processes, progress=not args.quiet)
    except _Usage as e:
        print(f"batch: {e} (see --help)", file=sys.stderr)
        return 2
    except (ValueError, OSError, RuntimeError) as e:
        print(f"batch: {' '.join(str(e).split())}", file=sys.stderr)
        return 1
    for failure in report.failed:
        print(f"batch: {failure}", file=sys.stderr)
    if not args.quiet:
        print(f"batch: {report}", file=sys.stderr)
    return 0 if report.ok else 1


if __name__ == "__main__":
    # The package's own module, not this __main__ copy, so that workers find the functions they are sent.
    from hapticfield.batch import main as _main

    sys.exit(_main())
