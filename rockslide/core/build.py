"""What the package build runs (``setup.py``): the core compiled into numba's cache before
installation, so that the first command after ``pip install`` loads machine code instead of
compiling for a minute. Nothing in rockslide imports this module: it imports the whole core, and
keeping it apart keeps the core's imports free of circles (`kernel` -> `compiled` only).
"""

from __future__ import annotations


def precompile() -> None:
    """Compile the core into numba's cache: `native.ENTRY_POINTS` with the argument types `simulate`
    gives them (`kernel.run` compiles every state's loop and every physics function it calls), the
    batch driver, and the intensity measures' oscillator when scipy is there. The package build runs
    this in the freshly built package (``setup.py``), before `native.build`; it is also what
    ``rockslide`` would otherwise do on its first run without the build's machine code."""
    import numpy as np

    from . import batch, layout, native, simulate

    jit = native.just_in_time()
    model = simulate.Model.from_block(0.1, 0.2, 0.5, 0.5, 0.8)
    settings = simulate.Settings(rotation=0.01)
    still = np.zeros(11)
    ground = simulate.ground_array(still, still, 0.01)
    st = simulate.initial_state(settings)
    history = np.empty((len(layout.HISTORY_COLUMNS), 16))
    events = np.zeros((16, len(layout.EVENT_COLUMNS)))
    jit.run(simulate.parameters(model, 0.01, settings), ground, jit.rest_bounds(ground), st, history, 1, 0, events,
            0)                     # the start only (every=1 would need a longer history): all is compiled
    jit.finished(st)
    R, alpha, _ = jit.block_constants(0.1, 0.2, 9.8)
    jit.kinetic_energy(0.0, 0.0, 0.0, 1.0, R, alpha)
    jit.potential_energy(0.0, 9.8, R, alpha)
    batch.warm_up()
    try:
        from . import intensity
    except ImportError:            # scipy is not needed to build the package
        return
    intensity.spectral_acceleration(still, 0.01, 0.5)
