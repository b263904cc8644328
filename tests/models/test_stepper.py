"""The one Stepper class, on every kind of packed system: play chains and Preisach systems.

Each stepper binds the compiled step kernel of its kind; these tests hold that fast path to
the batch run, bit for bit, with non-finite samples held and counted, and check that copies
and resets are independent.
"""

import numpy as np
import pytest

import hystcomp
from hystcomp import presets
from hystcomp._kernels import chain
from hystcomp._kernels import preisach as pk
from hystcomp._kernels._jit import step_function
from hystcomp.errors import InvalidParameterError, InvalidSignalError, InvalidTypeError
from hystcomp.models.hammerstein import HammersteinModel
from hystcomp.models.preisach import Preisach, PreisachStepper
from tests.conftest import random_walk

NON_FINITE = {7: np.nan, 300: np.inf, 301: np.nan, 1500: -np.inf}


def _table_model():
    # a table on a 9 x 9 grid, with a memory of 9 extrema so that the bound acts too
    poly = presets.paper_preisach()
    grid = np.linspace(0.0, 120.0, 9)
    table = poly.everett_function(grid[:, None], grid[None, :])
    return Preisach.from_parameters(table=table, max_extrema=9, output_offset=-2.0)


def _preisach_forward():
    return Preisach.from_parameters(theta=presets.PAPER_PREISACH_THETA, output_offset=-3.0)


SYSTEMS = {
    # name: (system, signal lower bound, upper bound, random-walk step)
    "pi compensator": (lambda: presets.paper_pi().inverse(), -2.0, 38.0, 1.5),
    "mpi compensator, slew limit": (
        lambda: presets.paper_mpi().inverse(slew_rate=4e4),
        -2.0,
        38.0,
        1.5,
    ),
    "preisach forward": (_preisach_forward, -5.0, 125.0, 6.0),
    "preisach forward, table": (_table_model, -5.0, 125.0, 6.0),
    "preisach multiplicative": (lambda: presets.paper_preisach().inverse(), -2.0, 38.0, 1.5),
    "preisach multiplicative, slew limit": (
        lambda: presets.paper_preisach().inverse(slew_rate=4e4),
        -2.0,
        38.0,
        1.5,
    ),
    "preisach exact": (lambda: presets.paper_preisach().inverse(method="exact"), -2.0, 38.0, 1.5),
}


@pytest.fixture(params=list(SYSTEMS))
def case(request, rng):
    """A system, a signal with non-finite samples, and the outputs a stepper must give."""
    make, lo, hi, step = SYSTEMS[request.param]
    system = make()
    u = random_walk(rng, 3000, lo, hi, step)
    for k, value in NON_FINITE.items():
        u[k] = value
    finite = np.isfinite(u)
    # a held sample leaves the state alone: the finite samples are a plain batch run, and
    # each non-finite one repeats the output before it
    expected = np.empty_like(u)
    expected[finite] = system.simulate(u[finite])
    last_finite = np.maximum.accumulate(np.where(finite, np.arange(u.size), 0))
    expected = expected[last_finite]
    return system, u, expected


def test_bound_step_equals_the_batch_run_bit_for_bit(case):
    system, u, expected = case
    stepper = system.stepper()
    # the fast path: the compiled entry point of the kind's step kernel, bound to the state
    # behind one type test of the sample
    assert stepper.step.func is step_function(stepper.kernels.step)
    assert stepper.step.state is stepper._p
    assert np.array_equal([stepper.step(uk) for uk in u], expected)
    assert stepper.nonfinite_count == len(NON_FINITE)
    assert stepper.last_output == expected[-1]
    # the documented method (the kernel through numba's dispatch) and blocks: the same bits
    other = system.stepper()
    assert np.array_equal([type(other).step(other, uk) for uk in u], expected)
    block = system.stepper()
    assert np.array_equal(np.concatenate([block.step_block(b) for b in np.split(u, 6)]), expected)
    assert block.nonfinite_count == len(NON_FINITE)


def test_copies_and_resets_are_independent(case):
    system, u, expected = case
    rest = system.stepper().last_output
    stepper = system.stepper()
    stepper.step_block(u[:1000])  # three of the non-finite samples held
    twin = stepper.copy()
    assert type(twin) is type(stepper)
    assert (twin.last_output, twin.nonfinite_count) == (expected[999], 3)
    # the twin runs on first: the original must not move
    assert np.array_equal([twin.step(uk) for uk in u[1000:]], expected[1000:])
    assert (stepper.last_output, stepper.nonfinite_count) == (expected[999], 3)
    assert np.array_equal([stepper.step(uk) for uk in u[1000:]], expected[1000:])
    # a reset goes back to the rest state, whatever the copy does
    twin.reset()
    assert (twin.last_output, twin.nonfinite_count) == (rest, 0)
    assert (stepper.last_output, stepper.nonfinite_count) == (expected[-1], len(NON_FINITE))
    assert np.array_equal([twin.step(uk) for uk in u], expected)
    stepper.reset()
    assert np.array_equal(stepper.step_block(u[:500]), expected[:500])
    assert twin.last_output == expected[-1]


@pytest.mark.parametrize(
    "kernels", [chain.CHAIN_KERNELS, pk.PREISACH_KERNELS], ids=["chain", "preisach"]
)
def test_step_kernel_is_compiled_with_the_flags_of_its_batch_kernel(kernels):
    step, run = kernels.step.targetoptions, kernels.run.targetoptions
    assert step["fastmath"] == run["fastmath"]
    assert step["_nrt"] is False  # no reference counting: the fast path's premise


def test_every_system_has_the_one_stepper_class():
    model = presets.paper_preisach()
    steppers = [
        presets.paper_pi().inverse().stepper(),
        presets.paper_mpi().stepper(),
        model.stepper(),
        model.inverse().stepper(),
        model.inverse(method="exact").stepper(),
    ]
    assert all(isinstance(s, hystcomp.Stepper) for s in steppers)
    assert [type(s).kernels for s in steppers[2:]] == [pk.PREISACH_KERNELS] * 3
    assert all(isinstance(s, PreisachStepper) for s in steppers[2:])
    assert all(type(s).kernels is chain.CHAIN_KERNELS for s in steppers[:2])


def _dynamic_compensator():
    dyn = hystcomp.LinearDynamics.from_parameters(
        sample_rate=20_000.0,
        resonance_hz=780.0,
        damping_ratio=0.05,
        creep_time_constants=[0.01, 0.1],
        creep_weights=[0.01, 0.01],
    )
    return HammersteinModel(presets.paper_mpi(), dyn).inverse()


@pytest.mark.parametrize(
    "make",
    [
        lambda: presets.paper_mpi().inverse().stepper(),
        lambda: presets.paper_preisach().inverse().stepper(),
        lambda: _dynamic_compensator().stepper(),
    ],
    ids=["chain", "preisach", "with dynamics"],
)
def test_a_deep_copy_or_a_pickled_stepper_steps_a_state_of_its_own(make):
    import copy
    import pickle

    s = make()
    s.step(10.0)
    for other in (copy.deepcopy(s), pickle.loads(pickle.dumps(s))):
        before = s.last_output
        expected = s.copy().step(25.0)
        assert other.step(25.0) == expected
        assert s.last_output == before  # the original did not move
        assert other.last_output == expected


def test_the_stepper_of_a_dynamic_compensator_checks_its_samples_and_its_preview():
    comp = _dynamic_compensator()
    s = comp.stepper()
    for bad in ("1.0", True, None, [1.0]):
        with pytest.raises(InvalidTypeError, match="real number"):
            s.step(bad)
    with pytest.raises(InvalidSignalError, match="preview"):
        s.prime(np.full(comp.preview + 1, 3.0))
    with pytest.raises(InvalidTypeError):
        s.step_block(["a", "b"])


def test_an_integer_beyond_the_floats_is_held_as_an_infinite_sample():
    s = presets.paper_mpi().inverse().stepper()
    held = s.step(10.0)
    assert s.step(10**400) == held
    assert s.step(-(10**400)) == held
    assert s.nonfinite_count == 2


@pytest.mark.parametrize(
    "packed",
    [np.zeros(3), np.full(30, 1e6), np.zeros((2, 20)), "abc"],
    ids=["short", "counts", "2-D", "text"],
)
def test_a_stepper_refuses_an_array_that_is_not_a_packed_chain(packed):
    with pytest.raises((InvalidParameterError, InvalidTypeError)):
        hystcomp.Stepper(packed)
    with pytest.raises((InvalidParameterError, InvalidTypeError)):
        hystcomp.Compensator(packed, kind="pi", voltage_range=(0.0, 120.0))


def test_a_compensator_is_built_only_with_the_clamp_its_packed_chain_holds():
    packed = presets.paper_pi().inverse().packed
    lo, hi = float(packed[chain.LOW]), float(packed[chain.HIGH])
    assert hystcomp.Compensator(packed, kind="pi", voltage_range=(lo, hi)).voltage_range == (lo, hi)
    with pytest.raises(InvalidParameterError, match="clamp held in 'packed'"):
        hystcomp.Compensator(packed, kind="pi", voltage_range=(lo, 5 * hi))
    with pytest.raises(InvalidParameterError, match="'kind'"):
        hystcomp.Compensator(packed, kind="banana", voltage_range=(lo, hi))
    broken = packed.copy()
    broken[chain.HEADER] = np.nan  # a parameter
    with pytest.raises(InvalidParameterError, match="non-finite"):
        hystcomp.Compensator(broken, kind="pi", voltage_range=(lo, hi))


def test_step_block_into_a_preallocated_out_equals_the_batch_run_bit_for_bit(case):
    system, u, expected = case
    stepper = system.stepper()
    out = np.empty(20)
    got = []
    for start in range(0, u.size - 20, 20):
        result = stepper.step_block(u[start : start + 20], out)  # views, as a loop has them
        assert result is out  # written in place, nothing allocated
        got.append(out.copy())
    n = len(got) * 20
    assert np.array_equal(np.concatenate(got), expected[:n])
    # a strided block and a list go the checked way, into the same out, with the same bits
    strided = np.repeat(u[n : n + 10], 2)[::2]
    assert not strided.flags.c_contiguous
    rest = stepper.step_block(strided, np.empty(10))
    assert np.array_equal(rest, expected[n : n + 10])
    assert stepper.nonfinite_count == sum(k < n + 10 for k in NON_FINITE)


def test_step_block_refuses_an_out_it_cannot_write_and_changes_nothing():
    stepper = presets.paper_mpi().inverse().stepper()
    u = np.linspace(0.0, 20.0, 20)
    before = stepper._p.copy()
    cases = [
        (np.empty(19), InvalidParameterError, "block's length \\(20\\)"),
        (np.empty(20, dtype=np.float32), InvalidTypeError, "float64 NumPy array"),
        ([0.0] * 20, InvalidTypeError, "float64 NumPy array"),
        (np.empty(40)[::2], InvalidParameterError, "not contiguous"),
        (u, InvalidParameterError, "overlaps the input block"),
    ]
    read_only = np.empty(20)
    read_only.setflags(write=False)
    cases.append((read_only, InvalidParameterError, "read-only"))
    for out, error, message in cases:
        with pytest.raises(error, match=message):
            stepper.step_block(u, out)
    shared = np.empty(30)
    with pytest.raises(InvalidParameterError, match="overlaps"):
        stepper.step_block(shared[:20], shared[10:30])  # a partial overlap, found by the kernel
    assert np.array_equal(stepper._p, before)  # no sample was run
    fresh = presets.paper_mpi().inverse().stepper()
    assert np.array_equal(stepper.step_block(u, np.empty(20)), fresh.step_block(u))


def test_the_step_of_a_chain_with_dead_zones_is_folded_to_the_batch_bits(rng):
    """The step sums its dead-zones in a register and stops at the first threshold the
    sample does not pass; the bits are the batch run's (forward MPI: dead-zones after the
    plays; inverse MPI: before)."""
    for system in (presets.paper_mpi(), presets.paper_mpi().inverse()):
        lo, hi = (-5.0, 125.0) if hasattr(system, "n_deadzones") else (-2.0, 38.0)
        u = random_walk(rng, 5000, lo, hi, 3.0)
        stepper = system.stepper()
        assert np.array_equal([stepper.step(uk) for uk in u], system.simulate(u))
    unsorted = chain.pack_chain(pre=(np.array([0.0, 2.0, 1.0]), np.array([1.0, 0.5, 0.5])))
    with pytest.raises(InvalidParameterError, match="dead-zone thresholds that decrease"):
        hystcomp.Stepper(unsorted)
