"""An AFM raster on the simulated scanner: uncompensated, per-axis and coupled compensation.

The experiment (``hystcomp raster``), on a :func:`~hystcomp.plant.scanner.raster_scanner`
of two or three coupled axes:

1. identification: the scanner's answer to ``hystcomp excite multiaxis`` (every axis over its
   range, independently of the others);
2. three ways to drive the raster: *uncompensated* (a straight line ``v_i = x_i / k_i`` per
   axis, ``k_i`` least squares through the origin on the record), *per-axis* (a hysteresis
   model per axis fitted to its own sensor's reading, coupling ignored: ``M = I``) and
   *coupled* (:class:`~hystcomp.models.multiaxis.MultiAxisModel`: each axis's model and the
   coupling);
3. the raster: the fast axis (X) a triangle at ``line_rate`` over 10-80 % of its stroke, the
   slow axis (Y) a ramp over 10-80 % of its stroke, one frame, the slow axis back (the
   retrace) and a second frame, measured on the second frame (the state a scanner is in
   while it images frame after frame); a third axis (Z) follows a topography of 10-80 % of
   its stroke, ``sin(2 pi x / p) sin(2 pi y / p)``;
4. each axis's tracking error (sensor reading minus reference), rms over the measured frame.

:func:`plot_raster` draws what an AFM would image of a checkerboard grating in each case: the
grating at the scanner's true position, placed where the reference says it is.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hystcomp import paper
from hystcomp.experiment.baseline import linear_gain
from hystcomp.identify.multiaxis_excitation import multiaxis_sequence
from hystcomp.models.multiaxis import MultiAxisModel
from hystcomp.plant.scanner import Scanner, raster_scanner

__all__ = [
    "METHODS",
    "RasterResult",
    "check_raster_folder",
    "plot_raster",
    "raster_experiment",
    "raster_reference",
    "write_raster",
]

#: The three ways to drive the raster, in the table's order.
METHODS = ("uncompensated", "per-axis", "coupled")
#: The reference spans this share of each axis's stroke.
SPAN = (0.1, 0.8)
#: The Z topography's period (µm) and the figure's grating pitch (µm).
PITCH_UM = 4.0


def raster_reference(
    strokes, *, lines: int = 64, line_rate: float = 10.0, sample_rate: float = paper.SAMPLE_RATE
):
    """The raster reference: two frames with the slow axis's retrace between them.

    Parameters
    ----------
    strokes : sequence of float
        Each axis's stroke, µm (X fast, Y slow, then Z).
    lines : int
        Lines per frame (one triangle period of the fast axis each).
    line_rate : float
        The fast triangle's frequency, Hz.
    sample_rate : float
        Hz.

    Returns
    -------
    t : ndarray, shape (n,)
        s.
    X_ref : ndarray, shape (n, N)
        µm.
    measured : slice
        The second frame, where the tracking is measured.
    """
    per_line = round(sample_rate / line_rate)
    frame = lines * per_line
    n = 3 * frame
    t = np.arange(n) / sample_rate
    lo, hi = SPAN
    phase = (t * line_rate) % 1.0
    tri = np.where(phase < 0.5, 2.0 * phase, 2.0 - 2.0 * phase)
    k = np.arange(n)
    ramp = np.interp(k, [0, frame, 2 * frame, n - 1], [0.0, 1.0, 0.0, 1.0])
    X = np.empty((n, len(strokes)))
    X[:, 0] = strokes[0] * (lo + (hi - lo) * tri)
    X[:, 1] = strokes[1] * (lo + (hi - lo) * ramp)
    if len(strokes) > 2:
        topo = np.sin(2 * np.pi * X[:, 0] / PITCH_UM) * np.sin(2 * np.pi * X[:, 1] / PITCH_UM)
        X[:, 2] = strokes[2] * (0.5 * (lo + hi) + 0.5 * (hi - lo) * topo)
    return t, X, slice(2 * frame, n)


@dataclass(frozen=True, eq=False)
class RasterResult:
    """What :func:`raster_experiment` measured.

    Attributes
    ----------
    rms_um : dict
        ``{method: ndarray of each axis's rms tracking error, µm}``.
    coupling : ndarray
        The scanner's true ``M``.
    identified : ndarray
        The coupled model's ``M``.
    kinds : list of str
        The coupled model's family per axis.
    t, X_ref : ndarray
        The reference.
    X : dict
        ``{method: the scanner's true positions (no sensor noise), (n, N)}``.
    measured : slice
        The measured frame.
    """

    rms_um: dict
    coupling: np.ndarray
    identified: np.ndarray
    kinds: list
    t: np.ndarray = field(repr=False)
    X_ref: np.ndarray = field(repr=False)
    X: dict = field(repr=False)
    measured: slice = field(repr=False)

    def ratio(self, method: str) -> np.ndarray:
        """Each axis's rms with ``method`` over its uncompensated rms.

        Parameters
        ----------
        method : str
            A method of the result.

        Returns
        -------
        numpy.ndarray
            One ratio per axis.
        """
        return self.rms_um[method] / self.rms_um["uncompensated"]

    @property
    def summed_ratio(self) -> float:
        """The axes' summed rms, coupled over per-axis."""
        return float(self.rms_um["coupled"].sum() / self.rms_um["per-axis"].sum())

    def csv_text(self) -> str:
        """Each axis's rms per method and its ratio to the uncompensated, as CSV.

        Returns
        -------
        str
            A header ``axis,method,rms_um,ratio_to_uncompensated`` and a row per axis and
            method (axes named x, y, z), the numbers in full precision.
        """
        rows = ["axis,method,rms_um,ratio_to_uncompensated"]
        for i in range(self.X_ref.shape[1]):
            for method in METHODS:
                rms = self.rms_um[method][i]
                rows.append(
                    f"{'xyz'[i]},{method},{rms!r},{rms / self.rms_um['uncompensated'][i]!r}"
                )
        return "\n".join(rows) + "\n"

    def table(self) -> list[str]:
        """The table ``hystcomp raster`` prints.

        Returns
        -------
        list of str
            The table's lines.
        """
        n = self.X_ref.shape[1]
        names = "XYZ"
        lines = [f"{'axis':<5}{'uncompensated':>15}{'per-axis':>17}{'coupled':>17}   (µm rms)"]
        for i in range(n):
            u = self.rms_um["uncompensated"][i]
            cells = [f"{u:15.4f}"]
            for method in METHODS[1:]:
                r = self.rms_um[method][i]
                cells.append(f"{r:9.4f} ({r / u:4.2f}x)")
            lines.append(f"{names[i]:<5}" + "".join(cells))
        per_axis, coupled = self.rms_um["per-axis"].sum(), self.rms_um["coupled"].sum()
        lines.append(
            f"sum  {self.rms_um['uncompensated'].sum():15.4f}{per_axis:17.4f}{coupled:17.4f}"
            f"   coupled / per-axis {coupled / per_axis:.2f}x"
        )
        return lines


def raster_experiment(
    scanner: Scanner | None = None,
    *,
    n_axes: int = 2,
    family="auto",
    lines: int = 64,
    line_rate: float = 10.0,
    n_jobs=None,
    seed: int = 0,
    excitation_frequency: float = 1.0,
) -> RasterResult:
    """Identify the scanner and image a raster three ways (module notes).

    Parameters
    ----------
    scanner : Scanner, optional
        The stage [``raster_scanner(n_axes, seed=seed)``].
    n_axes : {2, 3}
        Axes of the default scanner.
    family : {'auto', 'pi', 'mpi', 'preisach'}
        Each axis's model family, per-axis and coupled alike.
    lines, line_rate
        Of the raster (:func:`raster_reference`).
    n_jobs : int, optional
        Axes fitted in parallel (joblib).
    seed : int
        Seed of the default scanner's noise.
    excitation_frequency : float
        Rate of the identification input (``hystcomp excite multiaxis --frequency``): 2
        ramps twice as fast, a record half as long.

    Returns
    -------
    RasterResult
    """
    if scanner is None:
        scanner = raster_scanner(n_axes, seed=seed)
    n = scanner.n_axes
    fs = scanner.sample_rate
    _, V_id = multiaxis_sequence(n, sample_rate=fs, frequency=excitation_frequency)
    X_id = scanner.run(V_id)
    coupled = MultiAxisModel(family=family, n_jobs=n_jobs).fit(V_id, X_id)
    per_axis = MultiAxisModel(family=family, coupling=False, n_jobs=n_jobs).fit(V_id, X_id)
    strokes = [axis.stroke_um for axis in scanner.axes]
    t, X_ref, measured = raster_reference(strokes, lines=lines, line_rate=line_rate, sample_rate=fs)
    gains = np.array([linear_gain(V_id[:, i], X_id[:, i]) for i in range(n)])
    lo = np.array([a.voltage_range[0] for a in scanner.axes])
    hi = np.array([a.voltage_range[1] for a in scanner.axes])
    voltages = {
        "uncompensated": np.clip(X_ref / gains, lo, hi),
        "per-axis": per_axis.inverse().simulate(X_ref),
        "coupled": coupled.inverse().simulate(X_ref),
    }
    rms, true = {}, {}
    for method, V in voltages.items():
        X = scanner.run(V, seed=seed + 1)
        e = X[measured] - X_ref[measured]
        rms[method] = np.sqrt(np.mean(e**2, axis=0))
        true[method] = scanner.run_noiseless(V)
    return RasterResult(
        rms,
        np.asarray(scanner.coupling).copy(),
        np.asarray(coupled.coupling_).copy(),
        [a.kind for a in coupled.axes_],
        t,
        X_ref,
        true,
        measured,
    )


def grating(x, y, pitch: float = PITCH_UM) -> np.ndarray:
    """A checkerboard of squares ``pitch`` µm wide: 1 or 0 at the positions ``x, y`` (µm)."""
    return ((np.floor(x / pitch) + np.floor(y / pitch)) % 2.0).astype(np.float64)


def raster_image(result: RasterResult, method: str, columns: int = 160) -> np.ndarray:
    """The image an AFM forms on the measured frame's trace lines (the fast axis rising):
    each pixel the grating at the scanner's true position, placed at the reference's."""
    w = result.measured
    xr = result.X_ref[w, 0]
    x, y = result.X[method][w, 0], result.X[method][w, 1]
    rising = np.r_[np.diff(xr) > 0, False]
    edges = np.linspace(xr.min(), xr.max(), columns + 1)
    col = np.clip(np.searchsorted(edges, xr, side="right") - 1, 0, columns - 1)
    turns = np.flatnonzero(np.diff(rising.astype(int)) == 1) + 1
    line = np.searchsorted(turns, np.arange(xr.size), side="right")
    n_lines = int(line.max()) + 1
    image = np.full((n_lines, columns), np.nan)
    total = np.zeros((n_lines, columns))
    count = np.zeros((n_lines, columns))
    value = grating(x, y)
    np.add.at(total, (line[rising], col[rising]), value[rising])
    np.add.at(count, (line[rising], col[rising]), 1.0)
    seen = count > 0
    image[seen] = total[seen] / count[seen]
    return image


def plot_raster(result: RasterResult, path: str | Path) -> None:
    """The raster image of a checkerboard grating, three ways, with each axis's rms.

    Parameters
    ----------
    result : RasterResult
        The raster run.
    path : str or pathlib.Path
        The image's file.
    """
    from hystcomp.experiment._layout import fixed_layout, new_figure, save_figure

    fig = new_figure((10.5, 4.0))
    fixed_layout(fig, left=0.5, right=0.2, top=0.75, bottom=0.55, wgap=0.35, cols=3)
    axes = [fig.add_subplot(1, 3, i + 1) for i in range(3)]
    w = result.measured
    extent = (
        float(result.X_ref[w, 0].min()),
        float(result.X_ref[w, 0].max()),
        float(result.X_ref[w, 1].min()),
        float(result.X_ref[w, 1].max()),
    )
    titles = {"uncompensated": "uncompensated", "per-axis": "per-axis", "coupled": "coupled model"}
    for ax, method in zip(axes, METHODS, strict=True):
        image = raster_image(result, method)
        ax.imshow(image, origin="lower", extent=extent, aspect="auto", cmap="gray", vmin=0, vmax=1)
        rms = ", ".join(f"{'XYZ'[i]} {r:.3f}" for i, r in enumerate(result.rms_um[method]))
        ax.set_title(f"{titles[method]}\nrms µm: {rms}", fontsize=9)
        ax.set_xlabel("x reference (µm)")
    axes[0].set_ylabel("y reference (µm)")
    fig.suptitle(
        f"A {PITCH_UM:g} µm checkerboard imaged by a {result.X_ref.shape[1]}-axis scanner "
        "with coupled axes (10 Hz lines)",
        fontsize=10,
    )
    save_figure(fig, path, dpi=110)


def check_raster_folder(out_dir: str | Path) -> tuple[Path, Path]:
    """The table and the image :func:`write_raster` writes into ``out_dir``, checked before
    the run.

    Parameters
    ----------
    out_dir : str or pathlib.Path
        A folder, or a new one in an existing folder (made by :func:`write_raster`).

    Returns
    -------
    (pathlib.Path, pathlib.Path)
        ``raster.csv`` and ``raster.png`` in the folder.

    Raises
    ------
    InvalidParameterError
        ``out_dir`` is a file, or its parent folder does not exist.
    OutputPathError
        A file of the two exists and cannot be replaced
        (:func:`hystcomp.io.atomic.check_output_path`).
    """
    from hystcomp.errors import InvalidParameterError
    from hystcomp.io.atomic import check_output_path

    folder = Path(out_dir)
    if folder.exists() and not folder.is_dir():
        raise InvalidParameterError(
            f"The 'out_dir' argument of check_raster_folder must be a folder or a new name; "
            f"{str(folder)!r} is a file."
        )
    if not folder.parent.is_dir():
        raise InvalidParameterError(
            f"The 'out_dir' argument of check_raster_folder must be in an existing folder; "
            f"{str(folder.parent)!r} does not exist."
        )
    files = (folder / "raster.csv", folder / "raster.png")
    for path in files if folder.is_dir() else ():
        check_output_path(path)
    return files


def write_raster(result: RasterResult, out_dir: str | Path) -> list[Path]:
    """Write the table (``raster.csv``) and the image (``raster.png``) into ``out_dir``,
    both or neither.

    Parameters
    ----------
    result : RasterResult
        The raster run.
    out_dir : str or pathlib.Path
        The folder, made if it is missing (:func:`check_raster_folder`).

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    from hystcomp.io.atomic import write_all

    table, image = check_raster_folder(out_dir)
    table.parent.mkdir(exist_ok=True)
    text = result.csv_text()
    writers = {table: lambda tmp: tmp.write_text(text, encoding="utf-8")}
    return write_all({**writers, image: lambda tmp: plot_raster(result, tmp)})
