"""A warm start (issue 11): a command loads the libraries it needs when it needs them, and what a
run does to be quick changes nothing but its speed: its figure, drawn from the result kept in
memory, is the figure drawn from its file.

The speed itself is measured by benchmarks/bench_startup.py (results/bench_startup.md), not here.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from rockslide.api import runs as api_runs
from rockslide.api._shared import ANALYSIS_MODULES
from rockslide.cli import main
from rockslide.io import results

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "configs" / "example.yaml"
#: Libraries that take from a tenth of a second to most of one to load, and the commands that need them.
HEAVY = ("numpy", "matplotlib", "obspy", "h5py", "scipy", "numba", "dask", "distributed", "tqdm", "yaml", "PIL")


def loaded_after(*commands) -> list[list[str]]:
    """Run each command line (a list of arguments) in turn in one fresh interpreter, in the
    repository; give, after each, the `HEAVY` libraries loaded so far."""
    code = f"""
import json, sys
from rockslide.cli import main
seen = []
for args in json.loads(sys.argv[1]):
    try:
        main(args, prog_name="rockslide", standalone_mode=False)
    except SystemExit:
        pass
    seen.append(sorted(m for m in {HEAVY!r} if m in sys.modules))
print(json.dumps(seen))
"""
    done = subprocess.run([sys.executable, "-c", code, json.dumps([list(map(str, c)) for c in commands])],
                          cwd=REPO, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.splitlines()[-1])


def test_help_and_version_load_no_heavy_library():
    """``rockslide --help``, ``--version`` and every command's ``--help`` answer at once."""
    commands = [["--help"], ["--version"]] + [[name, "--help"] for name in sorted(main.commands)]
    assert loaded_after(*commands)[-1] == []


def test_a_run_loads_what_it_needs(tmp_path):
    """A run of AT2 records reads them without obspy; without its figure it loads no matplotlib;
    a run loads no dask or tqdm (a short one shows no progress bar); with the build's machine code
    (`core.native`) it loads no numba, and without it numba's JIT does the work."""
    from rockslide.core import native

    out = tmp_path / "out"
    no_plot, with_plot = loaded_after(["run", EXAMPLE, "--out-dir", out, "--no-plot"],
                                      ["run", EXAMPLE, "--out-dir", out, "--overwrite"])
    assert {"numpy", "h5py", "yaml"} <= set(no_plot)
    assert ("numba" in no_plot) == (native.ahead_of_time() is None)
    assert not {"matplotlib", "PIL", "obspy", "dask", "distributed", "tqdm"} & set(no_plot)
    assert "matplotlib" in with_plot
    assert not {"obspy", "dask", "distributed", "tqdm"} & set(with_plot)


def test_a_sweep_loads_no_numba_with_the_build(tmp_path):
    """A sweep on one thread (``--workers 1``) or two computes with the build's machine code case by
    case (`execute.local_kernel`; it releases the GIL, so two threads compute side by side): no
    numba, no scipy; without the build, numba's batch driver. Both give the same bits."""
    from rockslide.core import native

    out = tmp_path / "out"
    grid = ["sweep", EXAMPLE, "--mu", "0.4,0.5", "--pga", "500gal,700gal", "--no-plot", "--no-progress"]
    one, two = loaded_after([*grid, "--workers", "1", "--out-dir", out / "one"],
                            [*grid, "--workers", "2", "--out-dir", out / "two"])
    assert ("numba" in one) == (native.ahead_of_time() is None)
    assert "scipy" not in one or native.ahead_of_time() is None
    assert ("numba" in two) == (native.ahead_of_time() is None)
    one, two = (results.read_sweep(out / where / "example.sweep.h5").variables for where in ("one", "two"))
    assert one.keys() == two.keys()
    for name in one:
        assert one[name][0].tobytes() == two[name][0].tobytes(), name


def test_a_risk_of_a_given_fragility_loads_no_numba(tmp_path):
    """``rockslide risk --median --beta`` measures no record, runs no kernel and reads no case: it
    loads neither numba (the intensity measures' oscillator), scipy (the fits' statistics are
    `core.normal`'s), yaml and the case files' module, nor the engine, the fragility analysis (the
    intensity measures are `analyses.measures`) and the core's simulation (a risk file has no
    events)."""
    code = ("import sys\nfrom rockslide.cli import main\n"
            "main(sys.argv[1:], prog_name='rockslide', standalone_mode=False)\n"
            "print(sorted(m for m in ('numba', 'scipy', 'yaml', 'rockslide.case', 'rockslide.engine',"
            " 'rockslide.analyses.fragility', 'rockslide.core.simulate') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code, "risk", "--median", "0.5g", "--beta", "0.4", "--hazard",
                           str(REPO / "rockslide" / "hazard-example-PGA.csv"), "--out-dir", str(tmp_path),
                           "--no-plot"], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.splitlines()[-1] == "[]"


def test_a_fragility_analysis_of_peaks_on_one_thread_loads_no_numba(tmp_path):
    """A fragility analysis over PGA on one thread measures its records with numpy (an oscillator,
    for Sa, would load numba) and computes with the build's machine code: no numba with the build."""
    from rockslide.core import native

    [loaded] = loaded_after(["fragility", EXAMPLE, "--suite", REPO / "rockslide" / "suite-synthetic.yaml", "--levels",
                             "0.5g,1g", "--workers", "1", "--no-plot", "--out-dir", tmp_path])
    assert ("numba" in loaded) == (native.ahead_of_time() is None)


@pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="counts threads in /proc (Linux)")
@pytest.mark.parametrize("given", [None, "2"])
def test_the_command_gives_openblas_one_thread_unless_told(given):
    """The ``rockslide`` command (`cli.entry`) starts numpy's OpenBLAS with one thread, whose
    workers would otherwise spin for about 0.1 s of CPU after loading (a third of a run without
    figure): a run's threads are the main one and no BLAS worker. A value the user set is kept."""
    code = """
import atexit, os, sys
sys.argv = ["rockslide", "info", "records/synthetic_kt_h.at2"]
from rockslide import cli
atexit.register(lambda: print(os.environ.get("OPENBLAS_NUM_THREADS"), len(os.listdir("/proc/self/task"))))
cli.entry()
"""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if given is not None:
        env["OPENBLAS_NUM_THREADS"] = given
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, env=env,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    setting, threads = done.stdout.split()[-2:]
    assert setting == (given or "1")
    if given is None:
        assert threads == "1"


LEAVING = """
import atexit, sys, threading
from rockslide.cli import app
class Noisy:
    def __del__(self):
        print("torn down")
noisy = Noisy()
atexit.register(lambda: print("exit handler"))
print("buffered", end=" ")
{setup}
app.leave(SystemExit({code}))
"""


@pytest.mark.parametrize("left, torn_down", [
    ("", False),                                              # nothing left: no teardown
    ("threading.Thread(target=threading.Event().wait, args=(1,)).start()", True),     # a thread runs
    ("import h5py, tempfile; kept = h5py.File(tempfile.mktemp(suffix='.h5'), 'w')", True),   # a file open
])
def test_the_command_leaves_without_teardown_only_when_nothing_is_left(left, torn_down):
    """`app.leave` ends the process with ``os._exit`` (no unloading of modules, 0.06-0.1 s) only
    when the main thread is alone and no HDF5 file is open; either way the exit handlers run, what
    was printed is flushed and the exit code is the command's. Teardown shows by an object's
    ``__del__``, which only the interpreter's teardown calls."""
    done = subprocess.run([sys.executable, "-c", LEAVING.format(setup=left, code=3)], cwd=REPO, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 3, done.stderr[-3000:]
    assert done.stdout.startswith("buffered exit handler")
    assert ("torn down" in done.stdout) == torn_down


def test_a_message_exit_takes_the_usual_way():
    """``SystemExit("message")`` (exit code 1, the message on stderr) is the interpreter's to end."""
    done = subprocess.run([sys.executable, "-c", LEAVING.format(setup="", code="'a message'")], cwd=REPO,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 1
    assert done.stderr.strip().endswith("a message") and "torn down" in done.stdout


def test_the_modules_a_study_writes_with_load_while_it_computes():
    """`api._shared.importing_meanwhile` (a study's outputs: rockslide.io.results and h5py, and
    rockslide.plots with a figure): loaded by the end of the block, on a thread that is gone by
    then; a module that cannot be imported is left to fail where it is used, and the others load."""
    code = """
import sys, threading
from rockslide.api._shared import importing_meanwhile
assert "wave" not in sys.modules
with importing_meanwhile(["rockslide.io.results", "rockslide.no_such_module", "wave"]):
    pass
print("h5py" in sys.modules, "rockslide.io.results" in sys.modules, "wave" in sys.modules, threading.active_count())
"""
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.split() == ["True", "True", "True", "1"]


def test_a_study_loads_its_output_modules_meanwhile_only_on_the_builds_code(monkeypatch):
    """`api._shared.output_modules`: a local study on the build's machine code (whose threads import
    nothing) loads its output modules while it computes; on numba's JIT, the GPU or a cluster, which
    import modules of their own meanwhile, it loads them after."""
    from types import SimpleNamespace

    from rockslide.api._shared import output_modules
    from rockslide.core import native
    from rockslide.engine import execute

    drawn, bare = SimpleNamespace(plot=True), SimpleNamespace(plot=False)
    on_build = native.is_ahead_of_time()
    assert output_modules(drawn) == (["rockslide.io.results", "rockslide.plots"] if on_build else [])
    assert output_modules(bare) == (["rockslide.io.results"] if on_build else [])
    assert output_modules(drawn, device="gpu") == output_modules(drawn, scheduler="tcp://127.0.0.1:8786") == []
    assert output_modules(None) == []
    assert output_modules(bare, analysis=("numpy.ma",)) == (["rockslide.io.results", "numpy.ma"] if on_build else [])
    assert output_modules(None, analysis=("numpy.ma",)) == (["numpy.ma"] if on_build else [])
    assert output_modules(None, device="gpu", analysis=("numpy.ma",)) == []
    monkeypatch.setattr(execute, "local_kernel", lambda: None)          # numba's JIT: no build
    assert output_modules(drawn) == []


ANALYSED = """
import sys
from rockslide.api import _shared
from rockslide.cli.app import main
from rockslide.engine import execute
wanted = _shared.ANALYSIS_MODULES[{study!r}]
_shared.ANALYSIS_MODULES.update(dict.fromkeys(_shared.ANALYSIS_MODULES, ()))   # none meanwhile
compute = execute.compute
def computed(*args, **kwargs):
    done = compute(*args, **kwargs)
    print("after the compute", *[m in sys.modules for m in wanted])
    return done
execute.compute = computed
try:
    main({arguments!r}, standalone_mode=False)
finally:
    print("at the end", *[m in sys.modules for m in wanted])
"""


@pytest.mark.parametrize("study, arguments", [
    ("ensemble", ["run", "configs/example.yaml", "--ensemble", "20"]),
    ("fragility", ["fragility", "configs/example.yaml", "--suite", "records/suite-synthetic.yaml", "--levels",
                   "0.2g:1.0g:0.4g"]),
])
def test_the_analysis_modules_are_what_the_analysis_loads_after_the_compute(study, arguments, tmp_path):
    """`api._shared.ANALYSIS_MODULES`, which a study loads while it computes: with none loaded
    meanwhile, none of a study's is loaded when its compute ends, and each is by the end of the
    study (its analysis loads it), so that the list names what the analysis needs, no more.
    Without the build's machine code (an install without a C compiler, or core sources edited since
    the build) numba's JIT computes, and numba's import loads scipy and numpy.ma itself."""
    from rockslide.core import native

    if native.ahead_of_time() is None:
        pytest.skip("the build's machine code is not here or not of these sources (pip install -e . --no-deps): "
                    "numba's JIT loads numpy.ma before the analysis")
    arguments = [*arguments, "--no-plot", "--out-dir", str(tmp_path)]
    done = subprocess.run([sys.executable, "-c", ANALYSED.format(study=study, arguments=arguments)], cwd=REPO,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = [line.split() for line in done.stdout.splitlines() if line.startswith(("after", "at the end"))]
    wanted = len(ANALYSIS_MODULES[study])
    assert lines == [["after", "the", "compute", *["False"] * wanted], ["at", "the", "end", *["True"] * wanted]]


def test_a_run_needs_no_h5py_before_its_compute(tmp_path):
    """A run's history of at most `api.runs.HELD_HISTORY_ROWS` rows is held in memory and its file
    written after the compute: with nothing loaded meanwhile, h5py is not loaded when the compute
    starts, and is by the end (the file is written), so that it can load while the run computes."""
    code = f"""
import contextlib, sys
from rockslide.api import _shared, runs
from rockslide.cli.app import main
from rockslide.engine import prepare
runs.importing_meanwhile = lambda modules: contextlib.nullcontext()
simulate = prepare.simulate_prepared
def simulated(*args, **kwargs):
    print("at the compute", "h5py" in sys.modules)
    return simulate(*args, **kwargs)
prepare.simulate_prepared = simulated
main(["run", "configs/example.yaml", "--no-plot", "--out-dir", {str(tmp_path)!r}], standalone_mode=False)
print("at the end", "h5py" in sys.modules)
"""
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert [line for line in done.stdout.splitlines() if line.startswith("at ")] == ["at the compute False",
                                                                                    "at the end True"]
    assert (tmp_path / "example.h5").is_file()


def short_example(folder: Path) -> Path:
    """The shipped example on its own records, output every millisecond (22 000 rows): quick."""
    case = folder / "example.yaml"
    text = EXAMPLE.read_text().replace("../records/", str(REPO / "records") + "/")
    case.write_text(text.replace("output:  {dir: out}", "output:  {dir: out, interval: 1 ms}"))
    return case


@pytest.mark.parametrize("kept", [True, False])
def test_the_run_figure_is_the_figure_of_the_file(tmp_path, monkeypatch, kept):
    """The figure a run draws from the result it holds in memory is, byte for byte, the one
    ``rockslide plot`` draws from the file it wrote; a history longer than
    `api.runs.KEEP_HISTORY_ROWS` is read back from the file instead (same figure)."""
    case = short_example(tmp_path)
    out = tmp_path / "out"
    if kept:
        def no_reading_back(path):
            raise AssertionError("the run read its result back from the file")
        monkeypatch.setattr(results, "read_result", no_reading_back)
    else:
        monkeypatch.setattr(api_runs, "KEEP_HISTORY_ROWS", 1000)
    run = CliRunner().invoke(main, ["run", str(case), "--out-dir", str(out)])
    assert run.exit_code == 0, run.output
    monkeypatch.undo()
    redrawn = tmp_path / "redrawn.png"
    plot = CliRunner().invoke(main, ["plot", str(out / "example.h5"), "-o", str(redrawn)])
    assert plot.exit_code == 0, plot.output
    assert results.read_result(out / "example.h5").result.history["time"].size == 22_001
    assert (out / "example.png").read_bytes() == redrawn.read_bytes()


def compiled_by_commands(*commands) -> dict[str, int]:
    """Run `build.precompile` (what the package build does), then each command line in one
    fresh interpreter; give the core's functions that numba had to compile for the commands
    (cache misses), by name."""
    code = """
import json, sys
from rockslide.core import build
build.precompile()
from numba.core.registry import CPUDispatcher
from rockslide.core import batch, intensity, kernel, physics
modules = (batch, intensity, kernel, physics)
before = {f"{m.__name__}.{n}": sum(d.stats.cache_misses.values())
          for m in modules for n, d in vars(m).items() if isinstance(d, CPUDispatcher)}
from rockslide.cli import main
for args in json.loads(sys.argv[1]):
    main(args, prog_name="rockslide", standalone_mode=False)
missed = {f"{m.__name__}.{n}": sum(d.stats.cache_misses.values())
          for m in modules for n, d in vars(m).items() if isinstance(d, CPUDispatcher)}
print(json.dumps({name: n - before[name] for name, n in missed.items() if n > before[name]}))
"""
    done = subprocess.run([sys.executable, "-c", code, json.dumps([list(map(str, c)) for c in commands])],
                          cwd=REPO, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.splitlines()[-1])


@pytest.mark.slow
def test_after_the_build_compile_a_run_and_a_sweep_compile_nothing(tmp_path):
    """What the package build compiles (`build.precompile`) is every compiled function a run
    and a sweep call, with the argument types they call it with: a new user's first commands load
    machine code and compile nothing (cache misses are counted by numba per function)."""
    compiled = compiled_by_commands(
        ["run", EXAMPLE, "--out-dir", tmp_path, "--no-plot"],
        ["sweep", EXAMPLE, "--mu", "0.3:0.5:0.2", "--out-dir", tmp_path, "--no-plot", "--no-progress"])
    assert compiled == {}


def test_without_a_writable_cache_folder_the_core_compiles_in_memory(tmp_path):
    """Neither the installation's ``__pycache__`` nor the user's cache folder can be written (here:
    numba's in-tree locator refused, and HOME a plain file): importing the core still works, numba
    caches in a temporary folder for this process only, and that folder is gone at exit."""
    home = tmp_path / "home"
    home.write_text("not a folder")
    code = """
from numba.core import caching
caching.InTreeCacheLocator.from_function = classmethod(lambda cls, py_func, py_file: None)
from rockslide.core import compiled, physics
from numba.core import config
print(compiled.CACHE_IS_TEMPORARY, config.CACHE_DIR, physics.rock_acceleration(0.0, 0.0, 9.8, 1.0, 0.5, 0.3))
"""
    env = {key: value for key, value in __import__("os").environ.items()
           if key not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME")}
    env["HOME"] = str(home)
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, env=env,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    temporary, folder, acceleration = done.stdout.split()
    assert temporary == "True"
    assert float(acceleration) == 0.75 / 0.5 * (-9.8 * math.sin(0.3))    # eq. 3, still ground
    assert not Path(folder).exists()


# --- the build's ahead-of-time machine code (`core.native`) --------------------------------------

def _ground_cases():
    """Inputs that take a block through every state, with both event schemes, the energy ledger on
    and off, and history kept every step and every third step: (name, model, dt, ah, av, settings)."""
    from rockslide.core.simulate import Model, Settings

    dt = 0.01
    t = np.arange(0.0, 6.0, dt)
    envelope = np.minimum(1.0, t / 1.5) * np.exp(-0.3 * t)
    cases = []
    for name, peak, period, mu, e, vertical in [
            ("slides", 2.5, 0.5, 0.2, 0.9, 0.0),
            ("rocks", 6.0, 0.8, 0.9, 0.9, 0.0),
            ("rocks and slides", 7.0, 0.6, 0.4, 0.8, 0.5),
            ("overturns", 12.0, 1.2, 0.9, 0.95, 0.3),
            ("rests", 0.5, 0.5, 0.9, 0.9, 0.0)]:
        ah = peak * envelope * np.sin(2 * np.pi * t / period)
        av = vertical * peak * envelope * np.sin(2 * np.pi * t / (0.7 * period))
        model = Model.from_block(0.3, 0.8, mu, 0.9 * mu, e)
        for settings in (Settings(), Settings(events="step-end", energy=False, history_every=3)):
            cases.append((f"{name}, {settings.events}", model, dt, ah, av, settings))
    return cases


@pytest.fixture(scope="module")
def built_native(tmp_path_factory):
    """The entry points compiled ahead of time from the sources as they are, by `native.build` (what
    the package build runs), into a folder of this test and imported from there."""
    import importlib.util

    from rockslide.core import native

    folder = tmp_path_factory.mktemp("native")
    path = native.build(folder)
    spec = importlib.util.spec_from_file_location(native.MODULE_NAME, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert (folder / native.STAMP_FILE).read_text() == native.source_stamp()
    return module


def _releases_the_gil(path) -> bool:
    """Whether an extension module calls CPython's ``PyEval_SaveThread`` (its dynamic symbols name it):
    numba's wrappers of ``nogil`` functions call it before the machine code runs; without the flag,
    nothing in the module does."""
    return b"PyEval_SaveThread" in Path(path).read_bytes()


def test_the_builds_machine_code_releases_the_gil():
    """The installation's ahead-of-time module (`native.build`) releases the GIL while a case runs,
    so that a study's threads compute side by side on it (`execute.local_kernel`)."""
    from rockslide.core import native

    module = native.ahead_of_time()
    if module is None:
        pytest.skip("this installation has no build's machine code (no C compiler at install, or an edited core)")
    assert _releases_the_gil(module.__file__)


@pytest.mark.slow
def test_the_build_compiles_wrappers_that_release_the_gil(built_native):
    """`native.build` sets numba's ``release_gil`` flag for pycc, which has no option for it: a
    numba whose pycc no longer reads the flag fails here (its module would hold the GIL, and a
    study's threads would compute one after the other)."""
    assert _releases_the_gil(built_native.__file__)


def _same_result(a, b) -> bool:
    return (all(np.array_equal(a.history[name], b.history[name]) for name in a.history)
            and a.events.tobytes() == b.events.tobytes()
            and repr(a.summary) == repr(b.summary))        # repr: NaN fields compare equal


@pytest.mark.slow
def test_the_machine_code_of_the_build_is_numbas_to_the_last_bit(built_native, monkeypatch):
    """`native.build` compiles the same kernel as numba's JIT: every event time, history sample,
    extreme and energy of a run is the same bit for bit, in every state and with both event
    schemes (the inputs below visit all five states; the paper's records: test_paper.py runs
    through whichever the installation has)."""
    from rockslide.core import native, simulate

    jit = native.just_in_time()
    visited = set()
    for name, model, dt, ah, av, settings in _ground_cases():
        monkeypatch.setattr(native, "entry_points", lambda: jit)
        expected = simulate.simulate(model, dt, ah, av, settings)
        monkeypatch.setattr(native, "entry_points", lambda: built_native)
        got = simulate.simulate(model, dt, ah, av, settings)
        assert _same_result(expected, got), name
        visited.update(got.summary.states_seen)
    assert visited == {"REST", "SLIP", "ROCK", "ROCKSLIP", "OVERTURNED"}


@pytest.mark.slow
def test_a_batch_on_the_machine_code_of_the_build_is_numbas_to_the_last_bit(built_native, monkeypatch):
    """`simulate.compute_batch` (one thread's chunks: the build's `run` case by case) gives the final
    states of numba's batch driver (`batch.compute`) bit for bit, over a grid of cases that rest,
    slide, rock and overturn."""
    from rockslide.analyses import sweep as sw
    from rockslide.case import load_case
    from rockslide.core import batch, native, simulate

    plan = sw.plan_sweep(load_case(EXAMPLE), [sw.parse_axis("mu", "0.2:0.9:0.1"),
                                               sw.parse_axis("pga", "100gal:1500gal:200gal")],
                         records_dir=REPO / "records")
    inputs = (plan.case_params(), plan.case_states(), plan.base, plan.first, plan.count, plan.factor_h,
              plan.factor_v)
    expected = batch.compute(*inputs)
    monkeypatch.setattr(native, "entry_points", lambda: built_native)
    got = simulate.compute_batch(*inputs)
    assert got.tobytes() == expected.tobytes()
    modes = set(got[:, simulate.L.S_MODE].astype(int))
    assert {simulate.REST, simulate.OVERTURNED} <= modes and len(modes) >= 3


def test_edited_sources_run_on_numbas_jit(monkeypatch):
    """The build's machine code serves only the sources it was compiled from: once the core's
    sources differ from its stamp, a run uses numba's JIT (which recompiles them)."""
    from rockslide.core import native

    monkeypatch.setattr(native, "source_stamp", lambda: "an edited core")
    assert native.ahead_of_time() is None
    assert native.just_in_time().run.py_func.__module__ == "rockslide.core.kernel"


def test_the_figure_module_leaves_matplotlib_as_it_found_it():
    """`plots` imports matplotlib's drawing modules without generating the long docstrings of their
    artists' ``set`` (`plots._artists_without_set_docstrings`): ``set`` still sets properties and
    refuses unknown ones, and matplotlib's own method is back in place for classes defined later."""
    code = """
import matplotlib.artist as A
name = "_update_set_signature_and_docstring"
original = A.Artist.__dict__[name]
import rockslide.plots
from matplotlib.lines import Line2D
assert A.Artist.__dict__[name] is original
line = Line2D([0.0, 1.0], [0.0, 1.0])
line.set(linewidth=3.0, color="red")
assert line.get_linewidth() == 3.0 and line.get_color() == "red"
try:
    line.set(no_such_property=1)
except AttributeError as error:
    assert "no_such_property" in str(error)
else:
    raise AssertionError("an unknown property was accepted")
class Later(A.Artist):
    pass
assert "Supported properties are" in Later.set.__doc__
assert "Supported properties are" not in Line2D.set.__doc__
print("ok")
"""
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.split() == ["ok"]
