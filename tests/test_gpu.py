"""The GPU driver (`core.gpu`, ``--device gpu``): the same kernel as the CPU, tested everywhere.

No GPU is needed: numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``) runs the device kernel in
Python, with the CPU's arithmetic, so the device path must give exactly the CPU's final states. The
simulator has to be switched on before numba.cuda is first imported, so those tests run in a
subprocess of their own and leave this process (and the other tests) on the real CUDA target. On
a machine without a GPU, ``--device gpu`` must fail with one line.
"""

from __future__ import annotations

import importlib.util
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import cpu_as_device, invoke, one_line_error

from rockslide.core import batch, gpu
from rockslide.core import kernel as K
from rockslide.io import results

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "configs" / "example.yaml"
RECORDS = REPO / "records"
SUITE = RECORDS / "suite-synthetic.yaml"

needs_numba_cuda = pytest.mark.skipif(importlib.util.find_spec("numba_cuda") is None,
                                      reason="needs numba-cuda (pip install -e '.[test]')")


@pytest.fixture(scope="module", autouse=True)
def compiled():
    """Compile (or load) the CPU batch driver once, before any subprocess needs it."""
    batch.warm_up()


def simulated(*args, code=None):
    """Run ``rockslide ARGS`` (or Python ``code``) in a subprocess with the CUDA simulator on."""
    env = {**os.environ, "NUMBA_ENABLE_CUDASIM": "1"}
    command = [sys.executable, "-c", code] if code else [sys.executable, "-m", "rockslide", *map(str, args)]
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300, cwd=REPO)
    assert done.returncode == 0, done.stderr
    return done


def same_file_values(a: Path, b: Path) -> None:
    """Two result files hold exactly the same data variables (NaN equal to NaN)."""
    x, y = results.read_sweep(a), results.read_sweep(b)
    assert x.variables.keys() == y.variables.keys()
    for name, (values, _) in x.variables.items():
        other = y.variables[name][0]
        assert np.array_equal(values, other, equal_nan=values.dtype.kind == "f"), name


# The simulator's arithmetic is the CPU's: exact equality of every final state, not a tolerance.
# (On a real GPU the compiler fuses multiply-adds, which may move the last bits: there the check is
# the verdicts and a relative 1e-9 on the extremes, `benchmarks/bench_gpu.py --check`.)
EQUALITY_SCRIPT = """
import json, sys
import numpy as np
from pathlib import Path
from rockslide.analyses import sweep as sw
from rockslide.case import load_case
from rockslide.core import batch, gpu
from rockslide.engine import execute as ex
gpu.THREADS_PER_BLOCK = 4     # several blocks, one partly empty, on a small grid
case = load_case(Path("configs/example.yaml"))
axes = [sw.parse_axis("mu", "0.2,0.6"), sw.parse_axis("pga", "50gal,400gal,900gal"),
        sw.parse_axis("vertical_factor", "0,1")]
plan = sw.plan_sweep(case, axes, records_dir=Path("records"))
inputs = ex._chunk_inputs(plan, np.arange(plan.n_cases))
cpu = batch.compute(*inputs)
device = gpu.compute(*inputs)
order = gpu.launch_order(plan.case_params(), plan.base, plan.first, plan.count, plan.factor_h)
print(json.dumps({"identical": bool(np.array_equal(cpu, device, equal_nan=True)),
                  "modes": sorted(set(cpu[:, 0].tolist())), "n": plan.n_cases,
                  "reordered": bool((order != np.arange(plan.n_cases)).any()),
                  "simulator": gpu.cuda_simulator()}))
"""


@needs_numba_cuda
def test_simulated_device_gives_the_cpu_final_states_exactly():
    out = json.loads(simulated(code=EQUALITY_SCRIPT).stdout.strip().splitlines()[-1])
    assert out["simulator"]
    assert out["reordered"], "the grid should exercise the work ordering and its undoing"
    assert len(out["modes"]) > 1, "the grid should end in more than one state (rest and overturned)"
    assert out["identical"]


@needs_numba_cuda
def test_sweep_on_the_simulated_device_writes_the_cpu_values(tmp_path):
    axes = ["--mu", "0.2,0.6", "--pga", "100gal,900gal"]
    common = ["--records-dir", RECORDS, "--no-progress", "--no-plot", "--chunk-size", "2"]
    done = simulated("sweep", EXAMPLE, *axes, *common, "--out-dir", tmp_path / "gpu", "--device", "gpu")
    assert "on this machine's GPU" in done.stderr + done.stdout
    cpu = invoke("sweep", EXAMPLE, *axes, *common, "--out-dir", tmp_path / "cpu", "--device", "cpu")
    assert cpu.exit_code == 0, cpu.output
    same_file_values(tmp_path / "gpu" / "example.sweep.h5", tmp_path / "cpu" / "example.sweep.h5")


@needs_numba_cuda
def test_fragility_on_the_simulated_device_writes_the_cpu_values(tmp_path):
    common = ["--suite", SUITE, "--levels", "0.3g,1.5g", "--bootstrap", "0", "--records-dir", RECORDS,
              "--no-progress", "--no-plot"]
    simulated("fragility", EXAMPLE, *common, "--out-dir", tmp_path / "gpu", "--device", "gpu")
    cpu = invoke("fragility", EXAMPLE, *common, "--out-dir", tmp_path / "cpu")
    assert cpu.exit_code == 0, cpu.output
    x = results.read_dataset(tmp_path / "gpu" / "example.fragility.h5", format=results.FRAGILITY_FORMAT)
    y = results.read_dataset(tmp_path / "cpu" / "example.fragility.h5", format=results.FRAGILITY_FORMAT)
    assert x.variables.keys() == y.variables.keys()
    for name, (_, values, _) in x.variables.items():
        other = y.variables[name][1]
        assert np.array_equal(values, other, equal_nan=values.dtype.kind == "f"), name


# numba's performance warnings are advice to whoever writes a kernel ('Grid size 1 will likely result
# in GPU under-utilization', highlighted with terminal escape codes); rockslide chose the launch, so
# none may reach the user. The simulator emits none, so the launch is also made to emit them as
# numba-cuda's dispatcher does on a GPU (numba-cuda's class and numba's, which are distinct): the
# device path must swallow them, and only them.
WARNINGS_SCRIPT = """
import json, warnings
import numpy as np
from numba.core.errors import NumbaPerformanceWarning
from numba.cuda.core.errors import NumbaPerformanceWarning as CudaPerformanceWarning
from rockslide.core import batch, gpu

def performance(caught):
    return [str(w.message) for w in caught if issubclass(w.category, (NumbaPerformanceWarning, CudaPerformanceWarning))]

case = batch.warm_up_case()
with warnings.catch_warnings(record=True) as plain:
    warnings.simplefilter("always")
    first = gpu.compute(*case)

real = gpu.device_kernel()
emitted = []
class WarningKernel:
    def __getitem__(self, config):
        for category in (CudaPerformanceWarning, NumbaPerformanceWarning):
            warnings.warn(category("Grid size 1 will likely result in GPU under-utilization due to low occupancy."))
            emitted.append(category.__module__)
        warnings.warn(UserWarning("not a performance warning"))
        return real[config]
gpu._kernel = WarningKernel()
with warnings.catch_warnings(record=True) as launched:
    warnings.simplefilter("always")
    second = gpu.compute(*case)
print(json.dumps({"simulator": gpu.cuda_simulator(), "plain": performance(plain), "emitted": emitted,
                  "escaped": performance(launched), "others": [str(w.message) for w in launched],
                  "same": bool(np.array_equal(first, batch.compute(*case), equal_nan=True)
                                 and np.array_equal(first, second, equal_nan=True))}))
"""


@needs_numba_cuda
def test_no_numba_performance_warning_reaches_the_user():
    out = json.loads(simulated(code=WARNINGS_SCRIPT).stdout.strip().splitlines()[-1])
    assert out["simulator"] and out["same"]
    assert out["plain"] == []
    assert len(out["emitted"]) == 2, "the stand-in launch should have warned"
    assert out["escaped"] == [], "numba's performance warnings escaped the device path"
    assert out["others"] == ["not a performance warning"], "only performance warnings are swallowed"


def no_gpu_here() -> bool:
    try:
        gpu.require_device()
    except gpu.DeviceUnavailable:
        return True
    return False


@pytest.mark.parametrize("command", ["sweep", "fragility"])
def test_device_gpu_without_a_gpu_is_one_line(tmp_path, command):
    if not no_gpu_here():
        pytest.skip("this machine has a GPU")
    args = (["--mu", "0.3,0.5"] if command == "sweep" else ["--suite", SUITE, "--levels", "0.5g"])
    result = invoke(command, EXAMPLE, *args, "--records-dir", RECORDS, "--out-dir", tmp_path, "--device", "gpu")
    one_line_error(result, "--device")
    assert not any(tmp_path.iterdir())


def test_device_gpu_without_numba_cuda_names_the_extra(tmp_path, monkeypatch):
    real_find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "numba_cuda" else real_find_spec(name, *a))
    result = invoke("sweep", EXAMPLE, "--mu", "0.3,0.5", "--records-dir", RECORDS, "--out-dir", tmp_path,
                    "--device", "gpu")
    one_line_error(result, "--device", "pip install 'rockslide[gpu]'")


@pytest.mark.parametrize("extra, option", [(["--workers", "2"], "--workers"),
                                           (["--scheduler", "tcp://127.0.0.1:1"], "--device")])
def test_device_gpu_refuses_local_threads_and_a_cluster(tmp_path, extra, option):
    result = invoke("sweep", EXAMPLE, "--mu", "0.3,0.5", "--records-dir", RECORDS, "--out-dir", tmp_path,
                    "--device", "gpu", *extra)
    one_line_error(result, option)


def test_the_cpu_path_never_imports_numba_cuda(tmp_path):
    code = ("import sys; from rockslide.cli import main; "
            f"main(['sweep', {str(EXAMPLE)!r}, '--mu', '0.3,0.5', '--records-dir', {str(RECORDS)!r}, "
            f"'--out-dir', {str(tmp_path)!r}, '--no-plot', '--no-progress'], standalone_mode=False); "
            "print('numba.cuda' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "False"


# --------------------------------------------------------------------------------------------------
# Work ordering and its measure
# --------------------------------------------------------------------------------------------------


def cases(n, *, mu=0.5, n_sub=10.0):
    params = np.zeros((n, K.N_PARAMS))
    params[:, K.P_MU], params[:, K.P_TAN_ALPHA], params[:, K.P_G] = mu, 0.5, 10.0
    params[:, K.P_N_SUB], params[:, K.P_STEP] = n_sub, 0.001
    return params


def test_launch_order_puts_long_moving_cases_first_and_resting_cases_last():
    base = np.zeros((4, 300))
    base[0, :100] = 1.0          # record 0: 100 intervals, peak 1 m/s^2
    base[0, 100:300] = 2.0       # record 1: 200 intervals, peak 2 m/s^2
    params = cases(5)
    first = np.array([0, 100, 0, 100, 100])
    count = np.array([100, 200, 100, 200, 200])
    kh = np.array([10.0, 0.1, 6.0, 5.0, 3.0])   # threshold 5 m/s^2: cases 1 rest through
    order = gpu.launch_order(params, base, first, count, kh)
    assert order.tolist() == [3, 4, 0, 2, 1]


def test_warp_efficiency_counts_the_slowest_case_of_each_warp():
    params = cases(40)
    states = np.zeros((40, K.N_STATE))
    states[:, K.S_T_ROCK] = 0.001 * np.arange(40)          # case i: i steps
    useful, issued = gpu.warp_efficiency(states, params, np.arange(40))
    assert useful == pytest.approx(sum(range(40)))
    assert issued == pytest.approx(32 * 31 + 32 * 39)     # warps of cases 0-31 and 32-39 (padded)
    _, sorted_issued = gpu.warp_efficiency(states, params, np.arange(40)[::-1])
    assert sorted_issued == pytest.approx(32 * 39 + 32 * 7)


def test_the_host_prepares_and_stores_while_the_device_computes(tmp_path, monkeypatch):
    """`execute._compute_device` prepares launch k + 1 before it waits for launch k, and stores
    launch k after launch k + 1 has started: the device waits only for the copies (12 cases at 5 a
    launch: 3 launches of 4)."""
    from rockslide.analyses import sweep as sw
    from rockslide.case import load_case
    from rockslide.engine import chunks
    from rockslide.engine import execute as ex

    log = []
    cpu_as_device(monkeypatch, log=log)
    axes = [sw.parse_axis("mu", "0.2,0.4,0.6"), sw.parse_axis("pga", "100gal,300gal,600gal,900gal")]
    plan = sw.plan_sweep(load_case(EXAMPLE), axes, records_dir=RECORDS, chunk_size=2)
    ex.execute(plan, chunks.ChunkStore.beside(tmp_path / "x.sweep.h5", plan.key), device="gpu")
    assert log == [("prepare", 4), ("launch", 4),
                   ("prepare", 4), ("result", 4), ("launch", 4), ("store", 0),
                   ("prepare", 4), ("result", 4), ("launch", 4), ("store", 1),
                   ("result", 4), ("store", 2)]


def test_a_device_run_stores_a_chunk_a_launch_and_reads_nothing_back(tmp_path, monkeypatch):
    """On the GPU a chunk is up to a launch (`execute.device_chunks`: 12 cases at 5 a launch are 3
    chunks of 4, not the plan's 6 of 2), a launch holds the chunks that fit in
    `DEVICE_CASES_PER_LAUNCH` (a larger chunk goes alone), and the states come from the launches,
    not read back from the chunk files. The device here is the CPU's batch driver (`cpu_as_device`):
    what is tested is the launches and the files (the simulator tests above hold the device's
    arithmetic)."""
    from rockslide.analyses import sweep as sw
    from rockslide.case import load_case
    from rockslide.engine import chunks
    from rockslide.engine import execute as ex

    launched = []
    cpu_as_device(monkeypatch, lambda inputs: launched.append(len(inputs[0])))
    monkeypatch.setattr(ex, "collect", lambda *args: pytest.fail("the states were read back from the files"))
    axes = [sw.parse_axis("mu", "0.2,0.4,0.6"), sw.parse_axis("pga", "100gal,300gal,600gal,900gal")]
    cpu = ex.execute(sw.plan_sweep(load_case(EXAMPLE), axes, records_dir=RECORDS, chunk_size=2))
    for chunk_size, launches in ((2, [4, 4, 4]), (3, [4, 4, 4]), (6, [6, 6])):
        plan = sw.plan_sweep(load_case(EXAMPLE), axes, records_dir=RECORDS, chunk_size=chunk_size)
        store = chunks.ChunkStore.beside(tmp_path / f"{chunk_size}.sweep.h5", plan.key)
        launched.clear()
        done = ex.execute(plan, store, device="gpu")
        assert launched == launches
        assert done.chunks == done.store.count() == len(launches)
        assert done.store.folder != store.for_plan(plan.key).folder          # the device's own store
        assert np.array_equal(done.states, cpu.states, equal_nan=True)
        again = ex.execute(plan, store, device="gpu")                       # resumed: nothing to launch
        assert launched == launches and again.computed == 0
        assert np.array_equal(again.states, cpu.states, equal_nan=True)


def test_an_interrupted_device_run_says_where_its_chunks_are(tmp_path, monkeypatch):
    """Ctrl-C between launches: the exception carries the device's store and its chunk count, which
    the message names (`api.studies`), not the CPU's folder and chunking."""
    from rockslide import interrupts
    from rockslide.analyses import sweep as sw
    from rockslide.case import load_case
    from rockslide.engine import chunks
    from rockslide.engine import execute as ex

    launches = []

    def launched(inputs):
        launches.append(len(inputs[0]))
        if len(launches) == 2:
            os.kill(os.getpid(), signal.SIGINT)     # Ctrl-C during the second launch, which is stored

    cpu_as_device(monkeypatch, launched)
    axes = [sw.parse_axis("mu", "0.2,0.4,0.6"), sw.parse_axis("pga", "100gal,300gal,600gal,900gal")]
    plan = sw.plan_sweep(load_case(EXAMPLE), axes, records_dir=RECORDS, chunk_size=2)
    store = chunks.ChunkStore.beside(tmp_path / "x.sweep.h5", plan.key)
    with interrupts.handling_signals(), pytest.raises(interrupts.Interrupted) as stopped:
        ex.execute(plan, store, device="gpu")
    assert stopped.value.chunks == 3 and stopped.value.store.count() == 2
    assert stopped.value.store.folder == store.for_plan(plan.key).for_device("gpu").folder


def test_a_launch_holds_its_device_arrays_until_its_result(monkeypatch):
    """numba-cuda frees a dropped device array later, with others, and CUDA's free waits for the
    device: `gpu.Launch` keeps every array it sent until `Launch.result` has copied the states back,
    so that no free waits for its kernel while the host has work to do beside it. A stand-in for
    numba.cuda tells which arrays are alive (its kernel changes nothing: the states come back as
    they went, in the batch's order)."""
    import gc
    import types
    import weakref

    alive = []

    class DeviceArray:
        def __init__(self, array):
            self.array = np.array(array)
            alive.append(weakref.ref(self))

        def copy_to_host(self):
            return self.array.copy()

    class Kernel:
        def __getitem__(self, config):
            return lambda *arrays: None

    monkeypatch.setattr(gpu, "cuda", types.SimpleNamespace(to_device=DeviceArray))
    monkeypatch.setattr(gpu, "device_kernel", lambda: Kernel())
    params, states, base, first, count, kh, kv = batch.warm_up_case()
    params, states = np.repeat(params, 5, axis=0), np.repeat(states, 5, axis=0)
    states[:, K.S_MAX_X] = np.arange(5.0)                     # tells the cases apart
    order, host = gpu.prepare(params, states, base, first, count, kh, kv)
    launch = gpu.Launch(order, host)
    gc.collect()
    assert len(alive) == 7 and all(ref() is not None for ref in alive)
    final = launch.result()
    gc.collect()
    assert [ref() for ref in alive] == [None] * 7
    assert np.array_equal(final[:, K.S_MAX_X], np.arange(5.0))
