"""The public state of every stepper: save it, step, restore it, and the same samples give
the same outputs, bit for bit; a copy steps on its own.

Every kind of stepper the package makes is here: the play chains' and the Preisach
systems' (models and compensators), the inverse of the dynamics alone and in series with a
hysteresis compensator, many axes, a bank of channels and the simulated axis.
"""

import numpy as np
import pytest

from hystcomp import LinearDynamics, MultiAxisModel, presets
from hystcomp.errors import InvalidParameterError
from hystcomp.models.channels import ChannelBank
from hystcomp.models.hammerstein import HammersteinModel
from hystcomp.plant import Twin


def _dynamics():
    return LinearDynamics.from_parameters(
        sample_rate=20_000.0,
        resonance_hz=780.0,
        damping_ratio=0.05,
        creep_time_constants=[0.01, 0.1],
        creep_weights=[0.02, 0.01],
    )


def _multiaxis():
    axis = presets.paper_pi()
    return MultiAxisModel.from_parameters(axes=[axis, axis], coupling=[[1.0, 0.05], [0.0, 1.0]])


# name: (a stepper at its initial state, a block of inputs in its range)
STEPPERS = {
    "pi model": (lambda: presets.paper_pi().stepper(), "v"),
    "pi compensator": (lambda: presets.paper_pi().inverse().stepper(), "x"),
    "mpi model": (lambda: presets.paper_mpi().stepper(), "v"),
    "mpi compensator": (lambda: presets.paper_mpi().inverse(slew_rate=4e4).stepper(), "x"),
    "preisach model": (lambda: presets.paper_preisach().stepper(), "v"),
    "preisach multiplicative": (lambda: presets.paper_preisach().inverse().stepper(), "x"),
    "preisach exact": (
        lambda: presets.paper_preisach().inverse(method="exact").stepper(),
        "x",
    ),
    "inverse dynamics": (lambda: _dynamics().inverse().stepper(), "x"),
    "mpi with dynamics": (
        lambda: HammersteinModel(presets.paper_mpi(), _dynamics()).inverse().stepper(),
        "x",
    ),
    "preisach with dynamics": (
        lambda: HammersteinModel(presets.paper_preisach(), _dynamics()).inverse().stepper(),
        "x",
    ),
    "multi-axis model": (lambda: _multiaxis().stepper(), "V"),
    "multi-axis compensator": (lambda: _multiaxis().inverse().stepper(), "X"),
    "channel bank": (
        lambda: ChannelBank([presets.paper_pi(), presets.paper_mpi()]).stepper(),
        "V",
    ),
    "twin": (lambda: Twin().stepper(noise=False), "v"),
}


def _inputs(kind: str, rng, n: int = 400) -> np.ndarray:
    """A random walk of ``n`` samples: voltages (V) or references (µm), one column or two."""
    high = 120.0 if kind in ("v", "V") else 30.0
    columns = 2 if kind.isupper() else 1
    walk = np.cumsum(rng.normal(0.0, 0.05 * high, (n, columns)), axis=0)
    walk = np.abs((walk + 0.3 * high) % (2 * high) - high)  # folded into 0 .. high
    return walk[:, 0] if columns == 1 else walk


def _run(stepper, u: np.ndarray) -> np.ndarray:
    """One ``step`` per sample (a row per sample for many axes or channels)."""
    if u.ndim == 1:
        return np.array([stepper.step(float(s)) for s in u])
    return np.array([stepper.step(row) for row in u])


@pytest.fixture(params=list(STEPPERS))
def made(request, rng):
    make, kind = STEPPERS[request.param]
    u = _inputs(kind, rng)
    return make, u


def test_restored_state_repeats_the_outputs(made):
    make, u = made
    stepper = make()
    _run(stepper, u[:150])  # somewhere inside its memory
    saved = stepper.state
    first = _run(stepper, u[150:])
    assert not np.array_equal(stepper.state, saved)  # the steps moved it
    stepper.state = saved
    np.testing.assert_array_equal(_run(stepper, u[150:]), first)


def test_state_is_a_copy(made):
    make, u = made
    stepper = make()
    saved = stepper.state
    saved[:] = 1e6  # changes nothing in the stepper
    assert not np.array_equal(stepper.state, saved)
    np.testing.assert_array_equal(_run(stepper, u[:50]), _run(make(), u[:50]))


def test_copy_steps_on_its_own(made):
    make, u = made
    stepper = make()
    _run(stepper, u[:100])
    twin = stepper.copy()
    np.testing.assert_array_equal(twin.state, stepper.state)
    ahead = _run(stepper, u[100:])  # the original moves on; the copy stays where it was
    np.testing.assert_array_equal(_run(twin, u[100:]), ahead)


def test_state_moves_to_another_stepper_of_the_system(made):
    make, u = made
    one, other = make(), make()
    _run(one, u[:120])
    other.state = one.state
    np.testing.assert_array_equal(_run(other, u[120:]), _run(one, u[120:]))


def test_state_of_another_size_is_refused(made):
    make, _ = made
    stepper = make()
    with pytest.raises(InvalidParameterError, match=r"has \d+ values.*take it from \.state"):
        stepper.state = np.zeros(stepper.state.size + 1)


def test_noiseless_twin_stepper_leaves_the_twins_noise_alone():
    """A noiseless stepper draws nothing from the twin's generator: the runs after it are
    those of a twin that made none."""
    made, untouched = Twin(seed=3), Twin(seed=3)
    made.stepper(noise=False)
    v = np.linspace(0.0, 120.0, 200)
    np.testing.assert_array_equal(made.run(v), untouched.run(v))
    np.testing.assert_array_equal(made.stepper(noise=False).step_block(v), made.run_noiseless(v))
