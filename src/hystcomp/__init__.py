"""hystcomp: identify and compensate the hysteresis of piezoelectric actuators.

Implements the Preisach, Prandtl-Ishlinskii (PI) and Modified Prandtl-Ishlinskii (MPI)
models and their inverse-based compensators of "Experimental model inverse-based hysteresis
compensation on a piezoelectric actuator". Units: V, µm, s.

The names below are imported on first use (PEP 562), so that ``import hystcomp`` and the
command line's ``--help`` do not load numba and SciPy before anything is asked of them.

>>> import hystcomp
>>> model = hystcomp.presets.paper_mpi()
>>> comp = model.inverse()
>>> v = comp.simulate([0.0, 10.0, 20.0])
>>> bool(abs(model.simulate(v)[-1] - 20.0) < 1e-9)
True
"""

# No import at all up to here (nor __future__'s): the program's first lines come next
# (hystcomp._program, its signal handling). As typing.TYPE_CHECKING, to mypy too:
TYPE_CHECKING = False

__version__ = "0.1.0"

#: Public name -> (module, attribute in it; None for the module itself).
_LAZY = {
    "ChannelBank": ("hystcomp.models.channels", "ChannelBank"),
    "Compensator": ("hystcomp.models.compensator", "Compensator"),
    "LinearDynamics": ("hystcomp.models.dynamics", "LinearDynamics"),
    "ModifiedPrandtlIshlinskii": ("hystcomp.models.mpi", "ModifiedPrandtlIshlinskii"),
    "MultiAxisModel": ("hystcomp.models.multiaxis", "MultiAxisModel"),
    "PrandtlIshlinskii": ("hystcomp.models.pi", "PrandtlIshlinskii"),
    "Preisach": ("hystcomp.models.preisach", "Preisach"),
    "Record": ("hystcomp.io.records", "Record"),
    "Stepper": ("hystcomp.models.system", "Stepper"),
    "errors": ("hystcomp.errors", None),
    "evaluate": ("hystcomp.workflows.evaluate", "evaluate"),
    "fit_channels": ("hystcomp.models.channels", "fit_channels"),
    "load_model": ("hystcomp.io.models", "load_model"),
    "presets": ("hystcomp.presets", None),
    "read_record": ("hystcomp.io.records", "read_record"),
    "save_model": ("hystcomp.io.models", "save_model"),
    "to_control": ("hystcomp.control", "to_control"),
    "tracking_score": ("hystcomp.models.scorers", "tracking_score"),
}

__all__ = [  # written out for static tools; tests/cli/test_cli_lazy.py checks it against _LAZY
    "ChannelBank",
    "Compensator",
    "LinearDynamics",
    "ModifiedPrandtlIshlinskii",
    "MultiAxisModel",
    "PrandtlIshlinskii",
    "Preisach",
    "Record",
    "Stepper",
    "__version__",
    "errors",
    "evaluate",
    "fit_channels",
    "load_model",
    "presets",
    "read_record",
    "save_model",
    "to_control",
    "tracking_score",
]

if TYPE_CHECKING:  # what static tools see; at run time __getattr__ imports on first use
    from hystcomp import errors, presets
    from hystcomp.control import to_control
    from hystcomp.io.models import load_model, save_model
    from hystcomp.io.records import Record, read_record
    from hystcomp.models.channels import ChannelBank, fit_channels
    from hystcomp.models.compensator import Compensator
    from hystcomp.models.dynamics import LinearDynamics
    from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
    from hystcomp.models.multiaxis import MultiAxisModel
    from hystcomp.models.pi import PrandtlIshlinskii
    from hystcomp.models.preisach import Preisach
    from hystcomp.models.scorers import tracking_score
    from hystcomp.models.system import Stepper
    from hystcomp.workflows.evaluate import evaluate


def __getattr__(name: str):
    try:
        module, attribute = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'hystcomp' has no attribute {name!r}") from None
    import importlib  # here: the program's first lines import nothing (hystcomp._program)

    value = importlib.import_module(module)
    if attribute is not None:
        value = getattr(value, attribute)
    globals()[name] = value  # later look-ups do not come here again
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
