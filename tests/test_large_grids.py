"""Large sweeps: the scale axes planned apart (`sweep._Grid`), grids beyond 10^6 points, the memory
check, the chunk count, and collecting that reads each stored chunk once."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import invoke, one_line_error

from rockslide.analyses import sweep as sw
from rockslide.case import case_with, load_case
from rockslide.core import kernel as K
from rockslide.engine import chunks
from rockslide.engine import execute as ex
from rockslide.engine import plan as engine_plan
from rockslide.errors import CaseError

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "configs" / "example.yaml"
PULSE = REPO / "configs" / "spectrum-one-sine.yaml"
RECORDS = REPO / "records"


def one_point_plan(case, plan, index):
    """The plan of grid point ``index`` on its own: its case written with the point's values, planned
    as a grid of one point along an axis that is not a scale axis (restitution, at the point's own
    value), so that nothing of the two halves of `_Grid` is shared with the grid's plan."""
    combo = np.unravel_index(index, plan.shape)
    changes = {}
    for axis, i in zip(plan.axes, combo, strict=True):
        changes.update(sw.axis_changes(axis.name, axis.values[i], case, plan.mu_kinetic_ratio))
    point = case_with(case, changes)
    return sw.plan_sweep(point, [sw.parse_axis("restitution", repr(point.contact.restitution))],
                         records_dir=RECORDS)


def assert_point_planned_alike(plan, index, alone):
    """Point ``index`` of ``plan`` has the kernel inputs of its one-point plan ``alone``, bit for bit
    (the ground samples its window points at included)."""
    assert plan.case_params([index]).tobytes() == alone.case_params().tobytes()
    assert plan.case_states([index]).tobytes() == alone.case_states().tobytes()
    for name in ("factor_h", "factor_v", "record_end", "count"):
        assert getattr(plan, name)[index] == getattr(alone, name)[0], name
    own = plan.base[:, plan.first[index]:plan.first[index] + plan.count[index]]
    assert own.tobytes() == alone.base[:, alone.first[0]:alone.first[0] + alone.count[0]].tobytes()


@pytest.mark.parametrize("case_file, specs", [
    (EXAMPLE, [("pga", "300gal,900gal"), ("mu", "0.3,0.5,0.7"), ("vertical_factor", "0,2"),
               ("height_to_width", "2,3")]),
    (PULSE, [("amplitude", "0.3g,-1g"), ("period", "0.2,0.5"), ("mu", "0.3,0.8")]),
])
def test_scale_axes_planned_apart_equal_each_point_planned_alone(case_file, specs):
    """The scale axes (interleaved with the others, so that the indices of the two halves differ
    from the grid's) give every point the kernel inputs it gets when planned on its own."""
    case = load_case(case_file)
    plan = sw.plan_sweep(case, [sw.parse_axis(name, spec) for name, spec in specs], records_dir=RECORDS)
    assert plan.rows is not None and plan.params.shape[0] < plan.n_cases     # distinct rows only
    for index in range(plan.n_cases):
        assert_point_planned_alike(plan, index, one_point_plan(case, plan, index))


def test_a_grid_beyond_a_million_points_is_planned_in_distinct_rows():
    """1001 x 1000 points (the cap was 10^6): 1001 rows of parameters, not 10^6; points spread over
    the grid equal their one-point plans."""
    case = load_case(EXAMPLE)
    plan = sw.plan_sweep(case, [sw.parse_axis("mu", "0.3:0.7:0.0004"), sw.parse_axis("pga", "100gal:1099gal:1gal")],
                         records_dir=RECORDS)
    assert plan.shape == (1001, 1000) and plan.params.shape == (1001, K.N_PARAMS)
    assert plan.n_chunks == -(-plan.n_cases // engine_plan.MAX_CHUNK)
    for index in (0, 999, 1000, 523_417, plan.n_cases - 1):
        assert_point_planned_alike(plan, index, one_point_plan(case, plan, index))


def test_a_grid_beyond_the_memory_available_is_one_line(tmp_path, monkeypatch):
    """The memory a sweep needs (`SWEEP_BYTES_PER_CASE` a case) is compared with what the machine has
    before anything is planned: here 3 x 2 cases against 1000 bytes."""
    monkeypatch.setattr(engine_plan, "available_memory", lambda: 1000)
    result = invoke("sweep", EXAMPLE, "--mu", "0.3,0.5,0.7", "--pga", "300gal,600gal", "--records-dir", RECORDS,
                    "--out-dir", tmp_path, "--no-progress", "--no-plot")
    needed = 6 * engine_plan.SWEEP_BYTES_PER_CASE
    line = one_line_error(result, "--mu/--pga", f"6 cases need about {needed / 1e6:.3g} MB of memory",
                          "0.001 MB are available", "split the grid")
    assert f"{engine_plan.SWEEP_BYTES_PER_CASE} bytes a case" in line
    assert not list(tmp_path.iterdir())


def test_a_grid_beyond_the_largest_is_refused_before_planning():
    axes = [sw.parse_axis("mu", "0.1:0.99999:0.00001"), sw.parse_axis("pga", "1gal:1000gal:1gal"),
            sw.parse_axis("restitution", "0.5,0.6")]
    with pytest.raises(CaseError, match=f"at most {engine_plan.MAX_GRID_POINTS}"):
        sw.plan_sweep(load_case(EXAMPLE), axes, records_dir=RECORDS)


@pytest.mark.parametrize("n_cases", [1, 99, 25_600, 10**6, 10**7, 10**7 + 1, 10**8])
def test_chunks_stay_within_their_bounds(n_cases):
    """About 100 chunks for small studies, chunks of at most 256 cases up to 256 x 40000 cases, and
    never more than `MAX_CHUNK_FILES` chunk files."""
    size = engine_plan.default_chunk_size(n_cases)
    n_chunks = -(-n_cases // size)
    assert size >= engine_plan.MIN_CHUNK and n_chunks <= engine_plan.MAX_CHUNK_FILES
    if n_cases <= engine_plan.MAX_CHUNK * engine_plan.MAX_CHUNK_FILES:
        assert size <= engine_plan.MAX_CHUNK


def test_collecting_reads_each_stored_chunk_once(tmp_path, monkeypatch):
    """`execute` of a plan whose chunks are all stored reads each chunk file once (the check that it
    is intact gives its states), and returns them where `collect` would put them."""
    plan = sw.plan_sweep(load_case(EXAMPLE), [sw.parse_axis("mu", "0.3,0.5,0.7"), sw.parse_axis("pga", "1gal,2gal")],
                         records_dir=RECORDS, chunk_size=2)
    store = chunks.ChunkStore(tmp_path / "chunks", plan.key)
    rng = np.random.default_rng(1)
    for chunk in range(plan.n_chunks):
        indices = plan.chunk_indices(chunk)
        store.save(chunk, indices, rng.random((indices.size, K.N_STATE)))
    expected = chunks.collect(plan, store)
    reads = []
    original = chunks.ChunkStore.load
    monkeypatch.setattr(chunks.ChunkStore, "load", lambda self, c, i: reads.append(c) or original(self, c, i))
    done = ex.execute(plan, store)
    assert sorted(reads) == list(range(plan.n_chunks)) and done.computed == 0
    assert done.states.tobytes() == expected.tobytes()
