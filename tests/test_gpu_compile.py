"""The device kernel compiles for a real GPU (an H100, compute capability 9.0) with no GPU here.

numba's CUDA simulator (tests/test_gpu.py) runs the kernel in Python: it types nothing, so code that
only numba-cuda's real CUDA target rejects passes there and fails on the first real launch (a
``cuda.local.array`` shape read as ``K.N_STATE``, an attribute of another module, is typed int64
and not a compile-time constant: a TypingError on an H100). Two checks cover that:

- `test_run_cases_compiles_for_sm_90`: ``numba.cuda.compile_ptx`` of `core.gpu.run_cases`, the
  kernel as `core.gpu` defines it, for cc 9.0 and the argument types of the production launch. It
  runs numba-cuda's real CUDA pipeline end to end: typing, lowering to NVVM IR (the ``@njit``
  functions the kernel calls, `kernel.run` and everything below it, are compiled as CUDA device
  functions, as on a GPU), and NVVM to PTX. It needs no GPU and no driver, but it needs the CUDA
  toolkit's NVVM and NVRTC libraries, which pip installs as wheels (``numba-cuda[cu12]``); without
  them it fails and says so. It takes 100-150 s of one core on the 2-core development machine
  (2026-11-29; numba-cuda's inlining of the kernel's ``inline='always'`` functions, which copies
  their IR at each call, is half of it), a fifth of the suite: it starts in a process of its own as
  soon as the session has collected it (`start_compile`, called by conftest's
  ``pytest_collection_finish``), and computes on the second core while the other tests run on the
  first. The test then only waits for its result: the same check, about 2 minutes less wall.
- `test_device_array_shapes_are_module_constants`: a static look at the source (milliseconds), so
  that the rule the failure above broke is stated where the next kernel will be written.
"""

from __future__ import annotations

import ast
import importlib.util
import inspect
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from rockslide.core import gpu

REPO = Path(__file__).resolve().parents[1]

needs_numba_cuda = pytest.mark.skipif(importlib.util.find_spec("numba_cuda") is None,
                                      reason="needs numba-cuda (pip install -e '.[test]')")

#: What provides the toolkit libraries numba-cuda compiles with (NVVM, NVRTC, libdevice) as wheels.
TOOLKIT_WHEELS = "pip install 'numba-cuda[cu12]' (or: pip install nvidia-cuda-nvcc-cu12 nvidia-cuda-nvrtc-cu12)"

# Run in a subprocess of its own: numba.cuda must be the real CUDA target (NUMBA_ENABLE_CUDASIM off
# before numba.cuda is first imported), and the stand-in for the device below stays there.
COMPILE_SCRIPT = r"""
import json, sys, time
from types import SimpleNamespace

started = time.perf_counter()
from rockslide.core import batch, gpu
from rockslide.core import kernel as K

cuda = gpu.cuda_module()
import numba.cuda.dispatcher as dispatcher
from numba.cuda.cudadrv import devicearray, dummyarray

CC = (9, 0)    # an H100

# The @njit functions a kernel calls are compiled as device functions (`CUDADispatcher
# .compile_device`) for the current device's compute capability, which numba-cuda asks the driver
# for: here it is told CC, with no device. Nothing else stands in for the GPU.
dispatcher.get_current_device = lambda: SimpleNamespace(compute_capability=CC)
device_functions = set()
compile_device = dispatcher.CUDADispatcher.compile_device


def recording_compile_device(self, args, return_type=None):
    device_functions.add(f"{self.py_func.__module__}.{self.py_func.__qualname__}")
    return compile_device(self, args, return_type)


dispatcher.CUDADispatcher.compile_device = recording_compile_device

gpu.cuda = cuda    # as `gpu.device_kernel` sets it (which needs a GPU: `require_device`)


def device_type(host):
    # The numba type of `cuda.to_device(host)`, a DeviceNDArray of the host array's geometry, as the
    # CUDA dispatcher types a launch argument: numba-cuda's own rule (`DeviceNDArrayBase._numba_type_`)
    # on that geometry, with no device memory.
    dummy = dummyarray.Array.from_desc(0, host.shape, host.strides, host.dtype.itemsize)
    geometry = SimpleNamespace(ndim=dummy.ndim, strides=dummy.strides, size=dummy.size, dtype=host.dtype,
                               flags=dict(dummy.flags))
    return devicearray.DeviceNDArrayBase.__dict__["_numba_type_"].func(geometry)


# The production launch (`gpu.compute`) on `batch.warm_up_case`, up to the arrays it sends.
order, host = gpu.prepare(*batch.warm_up_case())
argtypes = tuple(device_type(a) for a in host)

out = {"simulator": gpu.cuda_simulator(), "run_case_is_kernel_run": gpu.run_case is K.run,
       "argtypes": [str(t) for t in argtypes]}
try:
    ptx, restype = cuda.compile_ptx(gpu.run_cases, argtypes, device=False, cc=CC)
except Exception as error:
    chain, e = [], error
    while e is not None and len(chain) < 10:
        chain.append(f"{type(e).__name__}: {e}")
        e = e.__cause__ or e.__context__
    text = "\n".join(chain)
    out["error"] = text
    out["missing_library"] = any(word in text for word in (
        "DynamicLibNotFoundError", "NvvmSupportError", "NvrtcSupportError", "libNVVM", "libnvvm",
        "libnvrtc", "libdevice"))
else:
    out["restype"] = str(restype)
    out["entry"] = ".entry" in ptx and "run_cases" in ptx
    out["target"] = next((line.split()[1] for line in ptx.splitlines() if line.startswith(".target")), None)
out["device_functions"] = sorted(device_functions)
out["seconds"] = round(time.perf_counter() - started, 1)
print(json.dumps(out))
"""


#: The compile's limit [s], from its start (up to 150 s on two cores with the rest of the suite beside it).
COMPILE_TIMEOUT = 900


class BackgroundCompile:
    """`COMPILE_SCRIPT` in a process of its own, started now; `result` waits for it. Its output goes
    to unnamed temporary files (no pipe to fill while nobody reads it), and its numba cache folder is
    its own, so that nothing it writes meets the other tests'."""

    def __init__(self):
        self._folder = tempfile.TemporaryDirectory(prefix="rockslide-sm90-")
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
        env["NUMBA_CACHE_DIR"] = self._folder.name
        self._stdout, self._stderr = tempfile.TemporaryFile(), tempfile.TemporaryFile()
        self._deadline = time.monotonic() + COMPILE_TIMEOUT
        self._process = subprocess.Popen([sys.executable, "-c", COMPILE_SCRIPT], env=env, cwd=REPO,
                                         stdout=self._stdout, stderr=self._stderr)

    def result(self) -> tuple[int, str, str]:
        """``(returncode, stdout, stderr)`` once the compile has ended (killed after `COMPILE_TIMEOUT`)."""
        try:
            self._process.wait(timeout=max(1.0, self._deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            self.stop()
            pytest.fail(f"compiling the device kernel for cc 9.0 took more than {COMPILE_TIMEOUT} s")
        texts = []
        for file in (self._stdout, self._stderr):
            file.seek(0)
            texts.append(file.read().decode(errors="replace"))
        return self._process.returncode, texts[0], texts[1]

    def stop(self) -> None:
        """End the process if it still runs, and remove its files."""
        if self._process.poll() is None:
            self._process.kill()
            self._process.wait()
        for file in (self._stdout, self._stderr):
            file.close()
        self._folder.cleanup()


_started: list[BackgroundCompile] = []


def start_compile() -> BackgroundCompile | None:
    """Start the compile of `test_run_cases_compiles_for_sm_90` (once; None without numba-cuda, where
    the test skips). conftest calls it when the session has collected that test, and ends it
    (`BackgroundCompile.stop`) when the session finishes."""
    if importlib.util.find_spec("numba_cuda") is None:
        return None
    if not _started:
        _started.append(BackgroundCompile())
    return _started[0]


@needs_numba_cuda
@pytest.mark.slow
def test_run_cases_compiles_for_sm_90():
    returncode, stdout, stderr = start_compile().result()
    assert returncode == 0, stderr
    out = json.loads(stdout.strip().splitlines()[-1])
    assert not out["simulator"]
    assert out["run_case_is_kernel_run"], "off the simulator, run_cases calls kernel.run itself"
    # params, states, base, bounds, count, history, events: C-contiguous, as cuda.to_device makes them
    assert out["argtypes"] == ["array(float64, 2d, C)"] * 4 + ["array(int64, 1d, C)"] + \
        ["array(float64, 2d, C)"] * 2, out["argtypes"]
    if out.get("missing_library"):
        pytest.fail("compiling the device kernel for a real GPU (no GPU needed) needs the CUDA toolkit's "
                    f"NVVM and NVRTC libraries, not found here: {TOOLKIT_WHEELS}\n{out['error']}")
    assert "error" not in out, f"run_cases does not compile for cc 9.0 (argument types {out['argtypes']}):\n" \
                               f"{out['error']}"
    assert out["restype"] == "none" and out["entry"], out
    assert out["target"] == "sm_90", out
    # the @njit functions were compiled as CUDA device functions, as on a GPU
    assert "rockslide.core.kernel.run" in out["device_functions"], out["device_functions"]
    assert any(name.startswith("rockslide.core.physics.") for name in out["device_functions"]), \
        out["device_functions"]


# --------------------------------------------------------------------------------------------------
# The rule, by reading the source
# --------------------------------------------------------------------------------------------------


def dotted(node: ast.AST) -> str | None:
    """``a.b.c`` of an attribute chain of names, else None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    return ".".join([node.id, *reversed(parts)])


def module_int_names(tree: ast.Module, namespace: dict) -> set[str]:
    """The names bound at module level (a plain assignment) whose value is an int."""
    names = set()
    for statement in tree.body:
        targets = (statement.targets if isinstance(statement, ast.Assign)
                   else [statement.target] if isinstance(statement, ast.AnnAssign) else [])
        for target in targets:
            if isinstance(target, ast.Name) and type(namespace.get(target.id)) is int:
                names.add(target.id)
    return names


def local_names(function: ast.FunctionDef) -> set[str]:
    """Parameters and names assigned inside a function (which would shadow a module constant)."""
    args = function.args
    names = {a.arg for a in [*args.posonlyargs, *args.args, *args.kwonlyargs, args.vararg, args.kwarg] if a}
    for node in ast.walk(function):
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
    return names


def device_functions(tree: ast.Module) -> dict[str, ast.FunctionDef]:
    """The functions of the module compiled for the device: those given to ``cuda.jit`` (as a call
    ``cuda.jit(...)(f)`` or as a decorator) and those of the module they call, transitively."""
    functions = {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef)}
    roots = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Call) and \
                (dotted(node.func.func) or "").endswith("cuda.jit"):
            roots.update(a.id for a in node.args if isinstance(a, ast.Name))
    for name, function in functions.items():
        for decorator in function.decorator_list:
            target = decorator.func if isinstance(decorator, ast.Call) else decorator
            if (dotted(target) or "").endswith("cuda.jit"):
                roots.add(name)
    found, todo = {}, [r for r in roots if r in functions]
    while todo:
        name = todo.pop()
        if name in found:
            continue
        found[name] = functions[name]
        for node in ast.walk(functions[name]):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in functions:
                todo.append(node.func.id)
    return found


#: The device arrays whose shape must be known when the kernel is compiled.
ARRAY_CONSTRUCTORS = ("local.array", "shared.array")


def bad_shapes(source: str, namespace: dict, module_name: str) -> tuple[list[str], int]:
    """Where a device function of a module (its source and its namespace) gives a device array a
    shape that is not an int literal or a module-level int of that module (or a tuple of those);
    and how many shapes were read."""
    tree = ast.parse(source)
    constants = module_int_names(tree, namespace)
    bad, seen = [], 0

    def fine(shape, shadowed):
        if isinstance(shape, ast.Constant):
            return type(shape.value) is int
        if isinstance(shape, ast.Name):
            return shape.id in constants and shape.id not in shadowed
        if isinstance(shape, ast.Tuple):
            return all(fine(e, shadowed) for e in shape.elts)
        return False

    for name, function in device_functions(tree).items():
        shadowed = local_names(function)
        for node in ast.walk(function):
            callee = dotted(node.func) if isinstance(node, ast.Call) else None
            if not callee or not callee.endswith(tuple("." + c for c in ARRAY_CONSTRUCTORS)):
                continue
            shape = node.args[0] if node.args else next((k.value for k in node.keywords if k.arg == "shape"), None)
            seen += 1
            if shape is None or not fine(shape, shadowed):
                text = ast.get_source_segment(source, shape) if shape is not None else "(none)"
                bad.append(f"{module_name}.{name}, line {node.lineno}: {callee}({text}, ...)")
    return bad, seen


def test_device_array_shapes_are_module_constants():
    """A device array's shape must be a compile-time constant on the real CUDA target: an int
    literal, or a name bound to an int at module level in the kernel's own module (numba freezes
    those). An attribute chain (``K.N_STATE``), an expression or a local is typed as a plain int64,
    which only the simulator accepts."""
    bad, seen = bad_shapes(inspect.getsource(gpu), vars(gpu), gpu.__name__)
    assert seen, "no cuda.local.array / cuda.shared.array found in the device functions of core.gpu"
    assert not bad, "device array shapes that are not compile-time constants:\n" + "\n".join(bad)


SAMPLE = """
import numpy as np
class K:
    N_STATE = 20
N = K.N_STATE
cuda = None
def run(x):
    st = cuda.local.array({shape}, np.float64)
    helper(x)
def helper(x):
    sh = cuda.shared.array({shared})
def build():
    return cuda.jit(cache=True)(run)
"""


@pytest.mark.parametrize("shape, shared, expected", [
    ("N", "(4, N), np.float64", []), ("20", "shape=(4, N), dtype=np.float64", []),
    ("K.N_STATE", "(4, N), np.float64", ["run", "K.N_STATE"]),              # what failed on an H100
    ("N + 1", "(4, N), np.float64", ["run", "N + 1"]),
    ("x.shape[0]", "(4, N), np.float64", ["run", "x.shape[0]"]),
    ("N", "(4, K.N_STATE), np.float64", ["helper", "(4, K.N_STATE)"]),      # in a function the kernel calls
    ("N", "shape=K.N_STATE, dtype=np.float64", ["helper", "K.N_STATE"]),
])
def test_the_shape_rule_flags_what_is_not_a_module_constant(shape, shared, expected):
    source = SAMPLE.format(shape=shape, shared=shared)
    namespace = {}
    exec(compile(source, "<sample>", "exec"), namespace)
    bad, seen = bad_shapes(source, namespace, "sample")
    assert seen == 2
    if not expected:
        assert bad == []
    else:
        assert len(bad) == 1 and all(word in bad[0] for word in expected), bad
