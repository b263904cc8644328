"""Models and compensators as python-control systems, for simulation and closed loops.

:func:`to_control` wraps a hysteresis model (voltage V -> displacement µm) or a compensator
(reference µm -> voltage V) as a discrete-time ``control.NonlinearIOSystem`` whose state
is the object's packed state, stepped by the same kernel as ``simulate``; so
``control.input_output_response`` reproduces ``simulate`` (to rounding, in practice bit for
bit), and the system composes with python-control's linear controllers and plants in
``control.interconnect``. Signals are named as in the rest of the package: a model has input
``v`` and output ``x``, a compensator input ``x_ref`` and output ``v``, so a compensator and
a model connect by name. Systems and states are named after what they are: a model after its
kind (``mpi``), a compensator after what it inverts (``inverse_mpi``), the simulated axis
``twin`` and the linear dynamics ``dynamics``; states after their slot (``play[3]``,
``last_output``, ``creep[0]``), never ``x[i]``, which would read as the displacement ``x``.

python-control is an optional dependency (``pip install "hystcomp[control]"``), imported
only when :func:`to_control` is called.

The simulated axis (:class:`hystcomp.plant.Twin`) converts too (input ``v``, output ``x``,
the noisy sensor reading), so a whole loop can be simulated with python-control; so do a
:class:`~hystcomp.models.dynamics.LinearDynamics` model (a linear state-space system) and a
compensator with the inverse of the dynamics (``model.inverse(dynamics=dyn)``).

Another kind of object plugs in with one function that describes it, at sample time ``dt``,
as a :class:`DiscreteSystem`, registered for its class with :func:`register`::

    @register(MyDynamics)
    def _dynamics(obj, dt):
        return DiscreteSystem(state=obj.initial_state(dt), update=..., output=...,
                              inputs=("v",), outputs=("x",))
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from hystcomp._validation import check_real
from hystcomp.errors import InvalidParameterError, InvalidTypeError

__all__ = ["DiscreteSystem", "register", "to_control"]


@dataclass(frozen=True)
class DiscreteSystem:
    """A discrete-time system as :func:`to_control` needs it (one input and output, or one
    per axis).

    Attributes
    ----------
    state : ndarray
        The initial state ``s[0]`` (1-D float64).
    update : callable
        ``update(s, u) -> s_next``: the state after applying input ``u`` in state ``s``
        (``u`` is the input vector, of one element, as python-control passes it).
    output : callable
        ``output(s, u) -> y``: the output for input ``u`` in state ``s`` (direct feedthrough
        allowed), a float, or an array of one value per output.
    inputs, outputs : tuple of str
        Signal names.
    name : str
        The system's default name (``to_control``'s ``name`` overrides it).
    states : tuple of str, optional
        A name per state slot; by default ``state[0]``, ``state[1]``, ...
    """

    state: np.ndarray
    update: Callable[[np.ndarray, np.ndarray], np.ndarray]
    output: Callable[[np.ndarray, np.ndarray], float | np.ndarray]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    name: str = "system"
    states: tuple[str, ...] | None = None

    def state_names(self) -> list[str]:
        """The name of each state slot (``states``, or ``state[i]``).

        Returns
        -------
        list of str
            One name per state slot.
        """
        if self.states is not None and len(self.states) == self.state.size:
            return list(self.states)
        return [f"state[{i}]" for i in range(self.state.size)]


Adapter = Callable[[object, float], DiscreteSystem]

#: (class, function) pairs: how to describe an object of that class as a DiscreteSystem.
_ADAPTERS: list[tuple[type, Adapter]] = []


def register(cls: type):
    """Decorator: ``function(obj, dt) -> DiscreteSystem`` describes the instances of ``cls``.

    ``dt`` is the sample time in s that :func:`to_control` was given. A later registration
    wins over an earlier one and over the built-in kinds.

    Parameters
    ----------
    cls : type
        The class whose instances the decorated function describes.

    Returns
    -------
    callable
        The decorator; it returns the function unchanged.
    """

    def decorate(function):
        _ADAPTERS.append((cls, function))
        return function

    return decorate


def _indexed(name: str, count: int) -> list[str]:
    return [f"{name}[{i}]" for i in range(count)]


#: Names of the counters and scratch slots that every packed state starts with.
_CHAIN_SLOTS = ("last_output", "held_count", "clamped_count", "step_input", "step_output")
_PREISACH_SLOTS = (
    "stack_top",
    "last_input",
    "last_hysteresis",
    "last_output",
    "held_count",
    "clamped_count",
)
_TWIN_SLOTS = ("input", "bouc_wen", "position", "velocity", "last_output", "held_count")


def packed_state_names(stepper) -> tuple[str, ...]:
    """A name for each slot of the state of a stepper's packed system (its layout's slots:
    :mod:`hystcomp._kernels.chain`, :mod:`~hystcomp._kernels.preisach` or
    :mod:`~hystcomp._kernels.twin`)."""
    from hystcomp._kernels import chain, preisach

    size = stepper.state.size
    if stepper.kernels is chain.CHAIN_KERNELS:
        fixed = [*_CHAIN_SLOTS, "step_work"]
        return tuple(fixed + _indexed("play", size - len(fixed)))
    if stepper.kernels is preisach.PREISACH_KERNELS:
        depth = (size - len(_PREISACH_SLOTS)) // 2
        return (*_PREISACH_SLOTS, *_indexed("extremum", depth), *_indexed("prefix_sum", depth))
    return tuple(_indexed("state", size))


def _stepped(
    stepper,
    inputs: tuple[str, ...],
    outputs: tuple[str, ...],
    name: str,
    states: tuple[str, ...] | None = None,
) -> DiscreteSystem:
    """A stepper of one input and one output as a DiscreteSystem.

    The state is the stepper's public ``state`` (for a packed system, the packed array's
    state part, its slots named by :func:`packed_state_names` unless ``states`` names
    them); one step of the stepper gives both the output and the next state. ``stepper``
    is this system's own (made for it, at its initial state): the two functions set its
    state, step it and read it.
    """
    initial = stepper.state

    def step(s: np.ndarray, u: np.ndarray) -> float:
        stepper.state = s
        return stepper.step(float(np.ravel(u)[0]))

    def update(s, u):
        step(s, u)
        return stepper.state

    def output(s, u):
        return step(s, u)

    return DiscreteSystem(
        state=initial,
        update=update,
        output=output,
        inputs=inputs,
        outputs=outputs,
        name=name,
        states=packed_state_names(stepper) if states is None else states,
    )


def _stepped_axes(stepper, model: bool) -> DiscreteSystem:
    """A multi-axis model (inputs ``v1..vN``, outputs ``x1..xN``) or compensator (inputs
    ``x1_ref..xN_ref``, outputs ``v1..vN``): its stepper's state, stepped by the stepper."""
    n = stepper.n_axes
    initial = stepper.state

    def update(s, u):
        stepper.state = s
        stepper.step(np.ravel(u))
        return stepper.state

    def output(s, u):
        stepper.state = s
        return stepper.step(np.ravel(u))

    names_in = [f"v{i + 1}" for i in range(n)] if model else [f"x{i + 1}_ref" for i in range(n)]
    names_out = [f"x{i + 1}" for i in range(n)] if model else [f"v{i + 1}" for i in range(n)]
    return DiscreteSystem(initial, update, output, tuple(names_in), tuple(names_out))


def _twin(twin, dt: float) -> DiscreteSystem:
    """The simulated axis: the kernel of ``Twin.run``, the sensor noise drawn per sample.

    The state is the axis's state (that of its noiseless stepper), then a sample counter; the
    noise of sample ``k`` comes from a generator seeded with the twin's seed, so a response
    is reproducible whatever python-control evaluates. The sensor reads the axis before the
    sample's voltage acts, so the output does not depend on the input (no algebraic loop in
    feedback).
    """
    from hystcomp._kernels import twin as kernels

    _check_rate(dt, twin.sample_rate, "the twin's", "build a Twin with another sample_rate instead")
    params = twin.params
    sigma = params.sensor_noise / params.sensor_gain
    stepper = twin.stepper(noise=False)  # the displacement and the offset: noise added below
    rest = stepper.state
    rng = np.random.default_rng(twin.seed)
    noise = np.empty(0)

    def noise_at(k: int) -> float:
        nonlocal noise
        while k >= noise.size:  # grows in order, so the draws do not depend on the calls
            noise = np.concatenate([noise, rng.standard_normal(4096)])
        return float(noise[k])

    def update(s, u):
        stepper.state = s[:-1]
        stepper.step(float(np.ravel(u)[0]))
        return np.append(stepper.state, s[-1] + 1.0)

    def output(s, u):
        # the reading before u acts: the input does not matter
        stepper.state = s[:-1]
        x = stepper.step(float(np.ravel(u)[0]))
        return x + sigma * noise_at(int(s[-1]))

    n_creep = rest.size - kernels.S_CREEP
    return DiscreteSystem(
        state=np.append(rest, 0.0),
        update=update,
        output=output,
        inputs=("v",),
        outputs=("x",),
        name="twin",
        states=(*_TWIN_SLOTS, "clamped_count", *_indexed("creep", n_creep), "sample"),
    )


def _linear_dynamics(dyn, dt: float) -> DiscreteSystem:
    """The linear dynamics ``D(z)`` (creep bank, then the modes) as a state-space system.

    The same transfer function as :meth:`LinearDynamics.simulate
    <hystcomp.models.dynamics.LinearDynamics.simulate>`, from rest at 0 (input ``v``, the
    output ``x`` of the hysteresis in µm, to the displacement ``x_d`` in µm).
    """
    from scipy.signal import tf2ss

    _check_rate(dt, dyn.sample_rate_, "the dynamics model's", "identify it at that rate")
    lags, weights = dyn.creep_lags, dyn.creep_weights_
    scale = 1.0 + float(np.sum(weights))
    # the creep bank, state s_i = w_i[k-1] of w_i = lfilter([1 - a_i], [1, -a_i], u):
    # y_c = (u + sum_i c_i w_i) / (1 + sum c),  s_i' = a_i s_i + (1 - a_i) u
    c_creep = weights * lags / scale
    d_creep = (1.0 + float(np.sum(weights * (1.0 - lags)))) / scale
    # then the resonance (b0 z + b1) / (z^2 + a1 z + a2), strictly proper, fed y_c (or the
    # two modes in parallel, one transfer function of order 4)
    b, a = dyn.resonance()
    a_res, b_res, c_res, _ = tf2ss(b, a)
    n, order = lags.size, a.size - 1
    A = np.zeros((n + order, n + order))
    A[:n, :n] = np.diag(lags)
    A[n:, :n] = np.outer(b_res[:, 0], c_creep)
    A[n:, n:] = a_res
    b_col = np.r_[1.0 - lags, b_res[:, 0] * d_creep]
    c_row = np.r_[np.zeros(n), c_res[0]]
    delay = dyn.delay_samples_
    names = (*_indexed("creep", n), *_indexed("resonance", 2))
    if delay < 0:  # the answer of the same sample: the output after this sample's update
        return DiscreteSystem(
            state=np.zeros(n + order),
            update=lambda s, u: A @ s + b_col * float(np.ravel(u)[0]),
            output=lambda s, u: float(c_row @ (A @ s + b_col * float(np.ravel(u)[0]))),
            inputs=("v",),
            outputs=("x",),
            name="dynamics",
            states=names,
        )
    # the latency: the last `delay` outputs in a line after the states, the oldest out
    m = n + order

    def update(s, u):
        out = np.empty_like(s)
        out[:m] = A @ s[:m] + b_col * float(np.ravel(u)[0])
        out[m:] = np.r_[c_row @ s[:m], s[m:-1]] if delay else s[m:]
        return out

    return DiscreteSystem(
        state=np.zeros(m + delay),
        update=update,
        output=lambda s, u: float(s[-1] if delay else c_row @ s),
        inputs=("v",),
        outputs=("x",),
        name="dynamics",
        states=(*names, *_indexed("latency", delay)),
    )


def _dynamic_compensator(obj, dt: float) -> DiscreteSystem:
    """The inverse of the dynamics, then the hysteresis compensator: the state of both.

    As the compensator's stepper, its input is the reference ``preview`` samples ahead
    (:attr:`~hystcomp.models.dynamic_compensator.DynamicCompensator.preview`).
    """
    if obj.sample_rate is not None:
        _check_rate(dt, obj.sample_rate, "the dynamics'", "identify them at the loop's rate")
    stepper = obj.stepper()
    n_dyn = stepper.dynamics_inverse.state.size
    names = (*_indexed("inverse_dynamics", n_dyn), *packed_state_names(stepper.hysteresis))
    return _stepped(stepper, ("x_ref",), ("v",), f"inverse_dynamics_{obj.kind}", names)


def _check_rate(dt: float, rate: float, whose: str, fix: str) -> None:
    if abs(dt * rate - 1.0) > 1e-9:
        raise InvalidParameterError(
            f"The 'dt' parameter of to_control must be {whose} sample time 1/{rate:g} s "
            f"= {1.0 / rate:g} s. Got {dt:g} s; {fix}."
        )


def _builtin_adapters() -> list[tuple[type, Adapter]]:
    # Imported here so that importing this module loads no kernel.
    from hystcomp.models.base import HysteresisModel
    from hystcomp.models.compensator import Compensator
    from hystcomp.models.dynamic_compensator import DynamicCompensator
    from hystcomp.models.dynamics import LinearDynamics
    from hystcomp.plant import Twin

    def _model(obj, dt) -> DiscreteSystem:
        return _stepped(obj.stepper(), ("v",), ("x",), obj.kind)

    def _compensator(obj, dt) -> DiscreteSystem:
        return _stepped(obj.stepper(), ("x_ref",), ("v",), f"inverse_{obj.kind}")

    def _multiaxis(obj, dt) -> DiscreteSystem:
        return _stepped_axes(obj.stepper(), obj.kind == "multiaxis" and hasattr(obj, "axes_"))

    from hystcomp.models.multiaxis import MultiAxisCompensator, MultiAxisModel

    return [
        (MultiAxisModel, _multiaxis),
        (MultiAxisCompensator, _multiaxis),
        (HysteresisModel, _model),
        (Compensator, _compensator),
        (Twin, _twin),
        (LinearDynamics, _linear_dynamics),
        (DynamicCompensator, _dynamic_compensator),
    ]


def _import_control():
    try:
        import control
    except ImportError:
        raise ImportError(
            "hystcomp.to_control needs python-control, an optional dependency. Install it "
            "with: pip install 'hystcomp[control]' (or pip install control)."
        ) from None
    return control


def describe(obj, dt: float) -> DiscreteSystem:
    """The :class:`DiscreteSystem` of ``obj`` at sample time ``dt`` (s), by its adapter."""
    adapters = _builtin_adapters() + _ADAPTERS
    for cls, function in reversed(adapters):  # the latest registration wins
        if isinstance(obj, cls):
            return function(obj, dt)
    kinds = ", ".join(sorted({cls.__name__ for cls, _ in adapters}))
    raise InvalidTypeError(
        f"The 'obj' parameter of to_control must be a hysteresis model or a compensator "
        f"(registered kinds: {kinds}). Got {type(obj).__name__}; build one with fit, "
        "load_model or model.inverse()."
    )


def _names(given, default) -> list[str]:
    """Signal names: one given as a str, several as a sequence, else the defaults."""
    if not given:
        return list(default)
    return [given] if isinstance(given, str) else list(given)


def to_control(obj, dt, *, name=None, inputs=None, outputs=None):
    """A discrete-time ``control.NonlinearIOSystem`` that runs a model or a compensator.

    Parameters
    ----------
    obj : HysteresisModel, Compensator, MultiAxisModel, MultiAxisCompensator or Twin
        A fitted model (input ``v`` in V, output ``x`` in µm), a compensator (input
        ``x_ref`` in µm, output ``v`` in V, clamped to its voltage range as always), a
        multi-axis model (inputs ``v1..vN``, outputs ``x1..xN``) or its compensator (inputs
        ``x1_ref..xN_ref``, outputs ``v1..vN``), or the simulated axis (input ``v``, output
        the sensor's reading ``x``), or an object of a kind added with :func:`register`.
    dt : float
        Sample time in s (``1 / sample_rate``; the twin's is 5e-5). A compensator built with
        a slew-rate limit should be given the ``sample_rate`` it was built for.
    name : str, optional
        System name for ``control.interconnect``; by default what the system is: the
        model's kind (``"pi"``, ``"mpi"``, ``"preisach"``, ``"multiaxis"``), ``"inverse_"``
        and the kind for a compensator (``"inverse_dynamics_mpi"`` with the inverse of the
        dynamics), ``"twin"`` or ``"dynamics"``. Two systems of one kind in one
        interconnection need names of their own (python-control renames and warns).
    inputs, outputs : str or sequence of str, optional
        Other signal names than the defaults above (one per axis for a multi-axis object).

    Returns
    -------
    control.NonlinearIOSystem
        One input and one output per axis; its state is the object's packed state, starting at the
        initial state (``sys.x0``), so ``control.input_output_response(sys, T, U, X0=sys.x0)``
        equals ``obj.simulate(U)``. The states are named after their slots (``play[0]``,
        ``last_output``, ``extremum[2]``, ``creep[0]``, ...).

    Raises
    ------
    ImportError
        If python-control is not installed (``pip install 'hystcomp[control]'``).
    InvalidTypeError
        If ``obj`` is of no registered kind.

    Notes
    -----
    The state is as large as the packed state: two slots per operator of a chain, and
    about twice ``max_extrema`` for a Preisach system (whose memory is bounded, see
    :class:`~hystcomp.models.preisach.Preisach`); ``input_output_response`` keeps the
    state of every sample, so for long Preisach runs prefer ``return_x=False``.

    Examples
    --------
    >>> import numpy as np, control, hystcomp
    >>> model = hystcomp.presets.paper_mpi()
    >>> sys = hystcomp.to_control(model, 5e-5)
    >>> v = np.array([0.0, 60.0, 120.0, 30.0])
    >>> res = control.input_output_response(sys, 5e-5 * np.arange(4), v, X0=sys.x0)
    >>> bool(np.allclose(res.outputs, model.simulate(v), rtol=0, atol=1e-12))
    True
    """
    dt = check_real(dt, "dt", "to_control", positive=True)
    system = describe(obj, dt)
    control = _import_control()
    sys = control.NonlinearIOSystem(
        lambda t, s, u, params: system.update(s, u),
        lambda t, s, u, params: np.atleast_1d(system.output(s, u)),
        inputs=_names(inputs, system.inputs),
        outputs=_names(outputs, system.outputs),
        states=system.state_names(),
        dt=dt,
        name=name if name is not None else system.name,
    )
    sys.x0 = system.state.copy()
    return sys
