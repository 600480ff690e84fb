"""Start-up of the command line (issue 11): warm runs, and with ``--cold`` the first runs after a
fresh install.

Prints Markdown and asserts nothing: the goals live here, never in the tests. ``make bench`` appends
``--cold`` to ``results/bench.md`` and writes the warm run to ``results/bench_startup.md``.

Warm (the default): numba's cache built and the byte code written (one untimed run of each command
first), then each command run ``--repeat`` times, each in a fresh process, as a user types it:
the ``rockslide`` script of this Python's environment (``--module``: ``python -m rockslide``).
The table gives the median and the range of the wall time and of the CPU time (the process and
its children, from ``getrusage``). PYTHONDONTWRITEBYTECODE is unset for the commands, as in a
user's shell. Then an import-time breakdown (``python -X importtime``) of the example's run: the
imports at the top of the import tree, those made on first use included (numba's first call
imports scipy.linalg, for one), median over three runs.

Last, the compression levels chosen for the result file and the figure, against the others.

Cold (``--cold``): a clone of the repository's HEAD (committed work only), a wheel built from it,
a new virtual environment with the wheel's dependencies; then ``--repeat`` times: the wheel
installed afresh (with no numba cache but what it ships) and an empty HOME (no ~/.cache: neither
numba's nor matplotlib's font list), and in the clone: the first ``rockslide run
configs/example.yaml``, the first ``rockslide sweep`` after it (a 2 x 2 grid: compiling the batch
kernel is the work), then the same run again, warm. Last, in that environment, the warm table
(each command 7 times): the issue's fresh-venv measurement of every figure. ``make bench`` appends
this to ``results/bench.md``. This takes minutes.

The machine is shared: the load average and the other busy processes are printed with the figures.

Usage: python benchmarks/bench_startup.py [--repeat N] [--module] [--cold] [--keep]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import platform
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
KOBE_CASE = Path("configs/table1/fig09b-mu052.yaml")
KOBE = ("kobe_jma_1995_ns_peer_rsn1106_kjm000.at2", "kobe_jma_1995_ud_peer_rsn1106_kjmup.at2")
GOALS = {"run": 1.0, "run --no-plot": 0.5, "run Kobe": 1.5}     # [s] warm, issue 11
#: Imports whose cost is not obvious from their name.
WHY = {
    "rockslide.plots": "matplotlib",
    "rockslide.results": "h5py",
    "rockslide.case": "yaml",
    "numba.np.arraymath": "numba's first call (its BLAS check imports scipy.linalg)",
    "numba.core.typing.cmathdecl": "numba's first call",
    "rockslide.cli": "click",
    "rockslide.records": "numpy (its first user)",
    "PIL.PngImagePlugin": "writing the PNG",
    "matplotlib.backends.backend_agg": "drawing",
}
#: Environment variables that would make a cold run warm (or a warm one cold).
CACHE_VARIABLES = ("NUMBA_CACHE_DIR", "MPLCONFIGDIR", "XDG_CACHE_HOME", "XDG_CONFIG_HOME", "PYTHONDONTWRITEBYTECODE",
                   "PYTHONPATH", "ROCKSLIDE_RECORDS")


def timed(command, *, cwd, env, timeout=900) -> tuple[float, float, subprocess.CompletedProcess]:
    """Run ``command``; its wall time and CPU time (user + system, its children included) [s]."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if done.returncode != 0:
        raise SystemExit(f"failed ({done.returncode}): {' '.join(map(str, command))}\n{done.stderr[-3000:]}")
    return wall, cpu, done


def spread(values) -> str:
    """``1.23 (1.10-1.40)``: the median and the range."""
    return f"{statistics.median(values):.2f} ({min(values):.2f}-{max(values):.2f})"


def machine() -> list[str]:
    """What the figures were measured on, and what else ran."""
    lines = [f"machine: {os.cpu_count()} cores ({cpu_model()}), {platform.system()} {platform.release()}, "
             f"Python {platform.python_version()}, {versions()}"]
    load = f"{os.getloadavg()[0]:.2f}" if hasattr(os, "getloadavg") else "unknown"
    busy = other_busy_processes()
    lines.append(f"load average at the start: {load}; busy processes besides this one: {busy or 'none'}")
    return lines


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def versions() -> str:
    from importlib.metadata import PackageNotFoundError, version
    out = []
    for name in ("numpy", "numba", "scipy", "matplotlib", "h5py"):
        try:
            out.append(f"{name} {version(name)}")
        except PackageNotFoundError:
            pass
    return ", ".join(out)


def other_busy_processes() -> str:
    """Processes using 10 % of a core or more (``ps``), this benchmark and ``ps`` itself left out."""
    try:
        ps = subprocess.run(["ps", "-eo", "pid=,pcpu=,comm="], capture_output=True, text=True, timeout=10).stdout
    except (OSError, subprocess.SubprocessError):
        return ""
    ours = {os.getpid(), os.getppid()}
    busy = []
    for line in ps.splitlines():
        pid, pcpu, comm = line.split(None, 2)
        if int(pid) not in ours and float(pcpu) >= 10.0 and comm.strip() != "ps":
            busy.append(f"{comm} {float(pcpu):.0f} %")
    return ", ".join(busy)


def user_env(**changes) -> dict:
    """The environment of a command: this one, with byte code written as in a user's shell."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    for key, value in changes.items():
        if value is None:
            env.pop(key, None)
        else:
            env[key] = value
    return env


def find_records() -> Path | None:
    candidates = [Path(os.environ["ROCKSLIDE_RECORDS"])] if os.environ.get("ROCKSLIDE_RECORDS") else []
    candidates.append(REPO.parent / "shared" / "records")
    return next((folder for folder in candidates if all((folder / n).is_file() for n in KOBE)), None)


# --------------------------------------------------------------------------------------------------
# Warm
# --------------------------------------------------------------------------------------------------


def warm(repeat: int, module: bool) -> None:
    script = Path(sys.executable).parent / "rockslide"
    rockslide = [sys.executable, "-m", "rockslide"] if module or not script.is_file() else [str(script)]
    records = find_records()
    out = Path(tempfile.mkdtemp(prefix="rockslide-bench-"))
    env = user_env(ROCKSLIDE_RECORDS=str(records.resolve()) if records else None)
    print(f"# Start-up of the command line, warm ({' '.join(rockslide[-2:]) if module else 'the rockslide script'})\n")
    for line in machine():
        print(line + "  ")
    warm_table(rockslide, REPO, env, out, repeat, records is not None)
    import_breakdown(env, out)
    choices(out)
    shutil.rmtree(out, ignore_errors=True)


def warm_table(rockslide: list[str], cwd: Path, env: dict, out: Path, repeat: int, kobe: bool) -> None:
    """The table of warm commands: each ``repeat`` times in a fresh process, after one untimed run."""
    commands = {
        "run": ["run", "configs/example.yaml", "--out-dir", out, "--overwrite"],
        "run --no-plot": ["run", "configs/example.yaml", "--out-dir", out, "--overwrite", "--no-plot"],
        "run Kobe": ["run", KOBE_CASE, "--out-dir", out, "--overwrite"] if kobe else None,
        "--help": ["--help"],
        "--version": ["--version"],
    }
    what = {"run": "`rockslide run configs/example.yaml` (HDF5 + PNG, 220 001 rows)",
            "run --no-plot": "`rockslide run configs/example.yaml --no-plot`",
            "run Kobe": f"`rockslide run {KOBE_CASE.as_posix()}` (150 s Kobe record, a row every 1 ms, HDF5 + PNG)",
            "--help": "`rockslide --help`", "--version": "`rockslide --version`"}
    print(f"each command {repeat} times in a fresh process, after one untimed run (numba's cache and the "
          "byte code in place); median (range) in seconds\n")
    print("| command | wall [s] | CPU [s] | goal (wall) |")
    print("|---|---:|---:|---:|")
    for key, args in commands.items():
        if args is None:
            print(f"| {what[key]} | - | - | needs the Kobe records ($ROCKSLIDE_RECORDS or ../shared/records) |")
            continue
        command = rockslide + [str(a) for a in args]
        timed(command, cwd=cwd, env=env)                               # warm numba's cache and the .pyc
        walls, cpus = [], []
        for _ in range(repeat):
            wall, cpu, _ = timed(command, cwd=cwd, env=env)
            walls.append(wall)
            cpus.append(cpu)
        goal = GOALS.get(key)
        verdict = "" if goal is None else f"<= {goal:.1f}: {'met' if statistics.median(walls) <= goal else 'not met'}"
        print(f"| {what[key]} | {spread(walls)} | {spread(cpus)} | {verdict} |")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"\nload average at the end: {load:.2f}\n")


_IMPORT_LINE = re.compile(r"^import time:\s+(\d+) \|\s+(\d+) \|( +)(\S+)$")


def import_breakdown(env: dict, out: Path, runs: int = 3) -> None:
    """The top of ``python -X importtime``'s tree for the example's run, median over ``runs``."""
    command = [sys.executable, "-X", "importtime", "-m", "rockslide", "run", "configs/example.yaml",
               "--out-dir", str(out), "--overwrite"]
    tops: dict[str, list[float]] = {}
    totals, walls = [], []
    for _ in range(runs):
        wall, _, done = timed(command, cwd=REPO, env=env)
        walls.append(wall)
        total = 0.0
        for line in done.stderr.splitlines():
            match = _IMPORT_LINE.match(line)
            if match and len(match.group(3)) == 1:                   # the top of the tree
                seconds = int(match.group(2)) * 1e-6
                tops.setdefault(match.group(4), []).append(seconds)
                total += seconds
        totals.append(total)
    print(f"## Where the imports go: `python -X importtime -m rockslide run configs/example.yaml` ({runs} runs)\n")
    print(f"all imports: {spread(totals)} s of a {spread(walls)} s run (importtime itself adds to both); "
          "the imports at the top of the tree taking 5 ms or more, with what they bring:\n")
    print("| import | ms (median) | what |")
    print("|---|---:|---|")
    shown = sorted(((statistics.median(v), name) for name, v in tops.items() if len(v) == runs), reverse=True)
    for seconds, name in shown:
        if seconds >= 0.005:
            print(f"| {name} | {1000 * seconds:.0f} | {WHY.get(name, '')} |")
    print()


def choices(out: Path, runs: int = 5) -> None:
    """The compression levels of the result file and of the figure, on the example's result."""
    import h5py
    import numpy as np
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    from rockslide import plots
    from rockslide.case import load_case
    from rockslide.engine.prepare import run_case
    from rockslide.io import results

    _, result = run_case(load_case(REPO / "configs" / "example.yaml"), REPO / "records")
    rows = result.history["time"].size
    print(f"## Compression levels, on the example's result ({rows} rows; best of {runs})\n")
    print("| file | level | write [ms] | read [ms] | size [KB] |")
    print("|---|---:|---:|---:|---:|")
    chosen = results._COMPRESSION
    try:
        for level in (1, 4):
            results._COMPRESSION = {**chosen, "compression_opts": level}
            path = out / f"gzip{level}.h5"
            write = min(_seconds(lambda p=path: results.write_result(p, result, name="x", overwrite=True))
                        for _ in range(runs))
            read = min(_seconds(lambda p=path: results.read_result(p)) for _ in range(runs))
            with h5py.File(path) as f:
                assert f["time_history/rotation"].compression_opts == level
            print(f"| HDF5 (gzip, shuffle) | {level}{' (used)' if level == chosen['compression_opts'] else ''} | "
                  f"{1000 * write:.0f} | {1000 * read:.0f} | {path.stat().st_size / 1024:.0f} |")
    finally:
        results._COMPRESSION = chosen
    canvas = FigureCanvasAgg(plots.response_figure(result, title="example"))
    canvas.draw()
    pixels = np.asarray(canvas.buffer_rgba())
    height, width, _ = pixels.shape
    image = Image.fromarray(pixels)

    def write_png(path, level):
        saved = plots.PNG_COMPRESSION
        plots.PNG_COMPRESSION = level
        try:
            with open(path, "wb") as handle:
                plots._write_png(handle, pixels, dpi=plots.DPI)
        finally:
            plots.PNG_COMPRESSION = saved

    def pillow(path, level):
        image.save(path, format="png", compress_level=level)

    ours, theirs = "PNG, rows unfiltered (`plots._write_png`)", "PNG, Pillow (adaptive row filters)"
    writers = [(ours, plots.PNG_COMPRESSION, " (used)", write_png), (ours, 6, "", write_png),
               (theirs, 3, "", pillow), (theirs, 6, " (Pillow's default)", pillow)]
    for number, (what, level, note, write) in enumerate(writers):
        path = out / f"figure{number}.png"
        seconds = min(_seconds(lambda p=path, z=level, w=write: w(p, z)) for _ in range(runs))
        print(f"| {what} {width} x {height} | {level}{note} | {1000 * seconds:.0f} | - | "
              f"{path.stat().st_size / 1024:.0f} |")
    print()


def _seconds(action) -> float:
    start = time.perf_counter()
    action()
    return time.perf_counter() - start


# --------------------------------------------------------------------------------------------------
# Cold
# --------------------------------------------------------------------------------------------------


def cold(repeat: int, keep: bool, warm_repeat: int = 7) -> None:
    folder = Path(tempfile.mkdtemp(prefix="rockslide-cold-"))
    say = lambda text: print(text, file=sys.stderr, flush=True)  # noqa: E731 - progress on stderr
    base = user_env(**{name: None for name in CACHE_VARIABLES})
    try:
        clone, venv, dist = folder / "clone", folder / "venv", folder / "dist"
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO,
                               capture_output=True, text=True, check=True).stdout.strip()
        say(f"cloning {REPO} at {head} into {clone}")
        subprocess.run(["git", "clone", "--quiet", "--no-hardlinks", str(REPO), str(clone)], check=True)
        say("building the wheel and a new virtual environment with its dependencies")
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        python = venv / "bin" / "python"
        pip = [str(python), "-m", "pip", "--disable-pip-version-check", "-q"]
        setup, _, _ = timed(pip + ["wheel", "--no-deps", "-w", str(dist), str(clone)], cwd=folder, env=base)
        wheel = next(dist.glob("rockslide-*.whl"))
        install, _, _ = timed(pip + ["install", str(wheel)], cwd=folder, env=base)
        rockslide = str(venv / "bin" / "rockslide")
        steps = {
            "first run": [rockslide, "run", "configs/example.yaml", "--overwrite"],
            "first sweep": [rockslide, "sweep", "configs/example.yaml", "--mu", "0.40,0.50", "--pga",
                            "500gal,700gal", "--overwrite", "--no-progress"],
            "run again": [rockslide, "run", "configs/example.yaml", "--overwrite"],
        }
        figures = {key: ([], []) for key in steps}
        notes = {}
        purelib = "import sysconfig; print(sysconfig.get_paths()['purelib'])"
        installed = Path(subprocess.run([str(python), "-c", purelib], capture_output=True, text=True,
                                        check=True).stdout.strip()) / "rockslide"
        for r in range(repeat):
            say(f"cold repetition {r + 1} of {repeat}: the wheel installed afresh, an empty HOME")
            # pip leaves what the package wrote beside itself (numba's cache): remove it all
            subprocess.run(pip + ["uninstall", "--yes", "rockslide"], check=True, env=base)
            shutil.rmtree(installed, ignore_errors=True)
            subprocess.run(pip + ["install", "--no-deps", str(wheel)], check=True, env=base)
            home = folder / f"home{r}"
            home.mkdir()
            shutil.rmtree(clone / "out", ignore_errors=True)
            env = {**base, "HOME": str(home)}
            for key, command in steps.items():
                wall, cpu, done = timed(command, cwd=clone, env=env)
                figures[key][0].append(wall)
                figures[key][1].append(cpu)
                said = [line.strip() for line in done.stderr.splitlines() if line.strip()]
                said += [line.strip() for line in done.stdout.splitlines() if "compil" in line]
                notes.setdefault(key, said[:2])
        say(f"warm commands, {warm_repeat} times each, in the same environment (the last HOME)")
        records = find_records()
        warm_env = {**env, "ROCKSLIDE_RECORDS": str(records.resolve())} if records else env
        with contextlib.redirect_stdout(io.StringIO()) as warm_text:
            warm_table([rockslide], clone, warm_env, folder / "warm-out", warm_repeat, records is not None)
    finally:
        if keep:
            say(f"kept {folder}")
        else:
            shutil.rmtree(folder, ignore_errors=True)
    print("# Start-up of the command line, cold\n")
    for line in machine():
        print(line + "  ")
    state = f"HEAD {head}" + (" (the working tree has uncommitted changes: not measured)" if dirty else "")
    times = f"{repeat} times" if repeat > 1 else "once"
    print(f"a clone of {state}, its wheel built ({setup:.0f} s, of which most is compiling the core into the "
          "numba cache the wheel carries: setup.py) and installed with its dependencies into a new "
          f"virtual environment ({install:.0f} s); then, {times}: the wheel installed afresh (no numba "
          "cache but what it ships), an empty HOME, and in the clone:\n")
    print("| step | wall [s] | CPU [s] | goal (wall) | what it said (stderr, and stdout about compiling) |")
    print("|---|---:|---:|---:|---|")
    goals = {"first run": "<= 10, with a note while compiling", "first sweep": "<= 10, with the same note",
             "run again": "<= 1.0 (warm)"}
    for key, command in steps.items():
        walls, cpus = figures[key]
        text = " / ".join(notes.get(key, [])).replace("|", "\\|") or "(nothing)"
        print(f"| `rockslide {' '.join(command[1:])}` | {spread(walls)} | {spread(cpus)} | {goals[key]} | {text} |")
    print()
    print("## Warm, in the same new environment\n")
    print(warm_text.getvalue())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=None, help="runs of each command (default 7 warm, 3 cold)")
    parser.add_argument("--module", action="store_true", help="time 'python -m rockslide' instead of the script")
    parser.add_argument("--cold", action="store_true", help="the first runs after a fresh install (minutes)")
    parser.add_argument("--keep", action="store_true", help="with --cold: keep the clone and the environment")
    args = parser.parse_args()
    if args.cold:
        cold(args.repeat or 3, args.keep)
    else:
        warm(args.repeat or 7, args.module)


if __name__ == "__main__":
    main()
