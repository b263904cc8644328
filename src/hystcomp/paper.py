"""Every number the paper publishes, in one place, each with where it is printed.

The paper is *Experimental model inverse-based hysteresis compensation on a piezoelectric
actuator* (see ``README.md``). Every other module takes these values from here, so that a
number of the paper is written once; ``tests/test_paper.py`` fails if a copy of one appears
elsewhere in ``src/``. This module imports nothing from hystcomp (it is a leaf: any layer may
use it) and holds plain tuples and floats, in hystcomp's units (V, µm, s, Hz).

What the paper leaves implicit, and how we read it (units of eq. 6, the *inverse* dead-zone
weights of eq. 22, eq. 17's ``max{x_p}``), is documented where the numbers become models:
:mod:`hystcomp.presets`.
"""

from __future__ import annotations

# --------------------------------------------------------------------- Section II: the rig

#: The actuator's nominal gain, µm/V: Section II, Tritor T-402, "gain 235 [nm/V]".
DATASHEET_GAIN = 0.235
#: The actuator's bandwidth, Hz: Section II, "bandwidth 630 Hz".
PIEZO_BANDWIDTH = 630.0
#: The capacitive sensor's gain, V/µm: Section II, CS005, "gain 200 [V/mm]".
SENSOR_GAIN = 0.2
#: The capacitive sensor's bandwidth, Hz: Section II, CS005, "bandwidth 8.5 kHz".
SENSOR_BANDWIDTH = 8_500.0
#: The acquisition's sample rate, Hz: Section II, "a sampling frequency of 20 kHz".
SAMPLE_RATE = 20_000.0
#: The piezo voltage ``v_px``, V: 0..120 V (Section III-A (i), the identification sinusoids
#: "from 0 to 120 V"; Section IV-A (ii), the triangles up to 120 V; ``max{v_px}`` of eq. 16).
VOLTAGE_RANGE = (0.0, 120.0)
#: Frequency of every identification signal, Hz: Sections II, III-A (i) and IV-A (ii).
IDENTIFICATION_FREQUENCY = 1.0

# ------------------------------------------------------- Section III-A: the Preisach model

#: Amplitudes of the Preisach identification sinusoids, V: Section III-A (i), "from 0 to
#: 120 V with a step of 5 V" (5, 10, ..., 120 V; an amplitude of 0 V is no signal).
PREISACH_AMPLITUDES = tuple(float(a) for a in range(5, 125, 5))
#: Eq. (6): the coefficients ``theta_0 .. theta_8`` of eq. (5), in eq. (5)'s order; read as
#: µm/V^k with alpha and beta in V (see :func:`hystcomp.presets.paper_preisach`).
PREISACH_THETA = (-0.137, 0.15, 0.0014, -0.0045, 0.00298, 2.5e-6, -7e-6, 1.9e-5, -1.4e-5)

# ---------------------------------------------------- Section IV-A: the PI and MPI models

#: Plays of the PI and MPI models, ``n + 1``: Section IV-A, "n + 1 = 16 backlashes".
N_OPERATORS = 16
#: Dead-zones of the MPI model, ``m + 1``: Section IV-A, "m + 1 = 16 dead-zone operators".
N_DEADZONES = 16
#: Amplitudes of the PI/MPI identification triangles, V: Section IV-A (ii), "30, 60, 90
#: and 120 V".
PI_AMPLITUDES = (30.0, 60.0, 90.0, 120.0)
#: Amplitudes of the sinusoids whose loops Fig. 5 shows, V: Section III-A, "sinusoidal
#: input of variable amplitude: 30, 60, 90 and 120 V" (the same values as the triangles).
FIG5_AMPLITUDES = PI_AMPLITUDES
#: Eq. (20): the PI play weights ``w_xH``, in µm/V (the printed ``10^-6`` m/V times 10^6).
PI_WEIGHTS = (
    0.1386,
    0.1101,
    0.0276,
    -0.0651,
    0.1568,
    -0.0698,
    0.0491,
    -0.0413,
    0.0396,
    0.0105,
    -0.0016,
    0.0232,
    -0.0957,
    0.0954,
    0.0323,
    -0.0685,
)
#: Eq. (21): the MPI play weights ``w_xH``, in µm/V (as eq. 20).
MPI_WEIGHTS = (
    0.4001,
    0.0492,
    0.0814,
    -0.0242,
    0.0886,
    0.0074,
    0.0548,
    0.0265,
    -0.0374,
    0.0378,
    0.0093,
    0.1146,
    -0.2047,
    0.0989,
    0.1547,
    -0.1286,
)
#: Eq. (22): the MPI dead-zone weights (unitless), read as the inverse weights ``w'_xS``
#: that eq. (19) identifies (see :mod:`hystcomp.presets`).
MPI_INVERSE_DEADZONE_WEIGHTS = (
    3.0803,
    -1.2216,
    0.1782,
    -0.2045,
    0.0502,
    0.0478,
    0.0894,
    -0.0221,
    -0.0336,
    0.0163,
    0.0620,
    0.2135,
    -0.0247,
    -0.1913,
    0.4753,
    -0.2476,
)

# ----------------------------------------------------- Section V: the tracking experiment

#: Frequencies of the triangle references, Hz: Section V (Fig. 10) and Table I.
FREQUENCIES = (1.0, 10.0, 50.0)
#: The four methods of Table I, in the paper's column order, and their display names.
METHODS = ("uncompensated", "preisach", "pi", "mpi")
LABELS = {"uncompensated": "uncompensated", "preisach": "Preisach", "pi": "PI", "mpi": "MPI"}
#: Table I: ``{frequency_hz: {method: (rms_um, max_um)}}``, as printed.
TABLE_I = {
    1.0: {
        "uncompensated": (4.6996, 7.3042),
        "preisach": (0.4182, 0.8807),
        "pi": (0.7975, 2.1765),
        "mpi": (0.3133, 0.6841),
    },
    10.0: {
        "uncompensated": (4.6659, 7.2417),
        "preisach": (0.5522, 1.3547),
        "pi": (0.9998, 2.7494),
        "mpi": (0.4436, 0.9556),
    },
    50.0: {
        "uncompensated": (4.660, 7.4270),
        "preisach": (1.1560, 2.4660),
        "pi": (1.1797, 3.0836),
        "mpi": (0.9688, 2.1547),
    },
}
#: Frequency of Fig. 9's triangle, Hz: "Fig. 9. ... for 1 Hz triangle input signal".
FIG9_FREQUENCY = 1.0
#: Section V, about Fig. 9 (1 Hz): hysteresis in the saturation zone, % of the range.
SATURATION_ZONE_PCT = {"uncompensated": 10.0, "preisach": 1.2, "pi": 3.3, "mpi": 0.5}
