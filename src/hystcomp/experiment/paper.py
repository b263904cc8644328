"""What the paper reports about its experiment (Section V), for comparison with ours."""

from __future__ import annotations

#: The four methods of Table I, in the paper's column order, and their display names.
METHODS = ("uncompensated", "preisach", "pi", "mpi")
LABELS = {"uncompensated": "uncompensated", "preisach": "Preisach", "pi": "PI", "mpi": "MPI"}

#: Table I: ``{frequency_hz: {method: (rms_um, max_um)}}``.
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

#: Section V, about Fig. 9 (1 Hz): hysteresis in the saturation zone, % of the range.
SATURATION_ZONE_PCT = {"uncompensated": 10.0, "preisach": 1.2, "pi": 3.3, "mpi": 0.5}

#: Section II: the actuator's nominal gain (Tritor T-402), µm/V.
DATASHEET_GAIN = 0.235
