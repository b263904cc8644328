"""From a measured record to a compensator running in C, checked against Python.

A lab's path from its own measurement to firmware, in one script:

1. read the record as it is (here the vendored micromanipulator record: no time column,
   200 Hz, a 0..3.6 V command, a sensor offset), naming its columns and sample rate;
2. identify a model with :func:`hystcomp.workflows.identify.identify_record`, fitting the first
   half and predicting the second, and print its report: the fit, the hold-out, and the
   compensator's estimated tracking beside a straight line's;
3. save the model file and export its compensator as C99 (``NAME.h``, ``NAME.c``);
4. compile the C with a small driver and run it on a reference (a 1 Hz triangle over 10..90 %
   of the measured displacement range), beside the same compensator's Python stepper: the
   two must agree to rounding (the C is compiled without numba's reassociation, so the last
   bits may differ), the check to run before flashing a controller.

Run it with ``python examples/record_to_c.py [RECORD] [--columns v=1,x=5] [--fs 200]
[--model {pi,mpi,preisach}] [--out DIR]``; it needs a C compiler ``cc``.

It printed (the vendored record, MPI)::

    MPI model (16 plays, 16 dead-zones) from tests/data/piezo-micromanipulator/Model_Vi_Do.dat
      ...
      hold-out:  last 4014 samples (50 %): model rms 0.3003 µm, straight line rms 3.344 µm: 11.1x better
    C compensator: record-to-c-out/c/stage.h, record-to-c-out/c/stage.c
    C against Python on a 1 Hz triangle of -118.1 .. -78.58 µm (400 samples):
      largest difference 3.11e-15 V (voltage 0.0246 .. 3.37 V)
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
from pathlib import Path

import numpy as np

import hystcomp
from hystcomp.codegen import export_c
from hystcomp.io.records import parse_columns
from hystcomp.workflows.identify import identify_record

RECORD = Path(__file__).resolve().parents[1] / "tests/data/piezo-micromanipulator/Model_Vi_Do.dat"
FLAGS = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic"]

# Reads one reference (µm) per line from stdin and prints the voltage (V) of each.
DRIVER = """
#include <stdio.h>
#include "stage.h"

int main(void) {
    stage_state s;
    double x_ref;
    stage_init(&s);
    while (scanf("%lf", &x_ref) == 1) {
        printf("%.17g\\n", stage_step(&s, x_ref));
    }
    return 0;
}
"""


def triangle(low: float, high: float, sample_rate: float, periods: int = 2) -> np.ndarray:
    """A 1 Hz triangle from ``low`` up to ``high`` and back, ``periods`` times (µm)."""
    phase = np.arange(int(periods * sample_rate)) / sample_rate % 1.0
    return low + (high - low) * (1.0 - np.abs(2.0 * phase - 1.0))


def run_c(folder: Path, reference: np.ndarray) -> np.ndarray:
    """The exported compensator in ``folder``, compiled with :data:`FLAGS`, run on ``reference``."""
    cc = shutil.which("cc")
    if cc is None:
        raise SystemExit("record_to_c: no C compiler 'cc' on this machine")
    (folder / "driver.c").write_text(DRIVER)
    program = folder.resolve() / "drive"  # cc runs in the folder: a relative path would nest
    build = [cc, *FLAGS, "-o", str(program), "stage.c", "driver.c", "-lm"]
    subprocess.run(build, cwd=folder, check=True)
    text = "\n".join(f"{x:.17g}" for x in reference)
    done = subprocess.run([str(program)], input=text, capture_output=True, text=True, check=True)
    return np.array(done.stdout.split(), dtype=float)


def main(argv: list[str] | None = None) -> dict:
    """Run the example; return the figures it printed (for the tests)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("record", nargs="?", type=Path, default=RECORD)
    parser.add_argument("--columns", default="v=1,x=5", help="as hystcomp identify --columns")
    parser.add_argument("--fs", type=float, default=200.0, help="sample rate, Hz")
    parser.add_argument("--model", default="mpi", choices=("pi", "mpi", "preisach"))
    parser.add_argument("--out", type=Path, default=Path("record-to-c-out"))
    args = parser.parse_args(argv)

    record = hystcomp.read_record(
        args.record, columns=parse_columns(args.columns), sample_rate=args.fs
    )
    result = identify_record(record, args.model, holdout=0.5)
    print("\n".join(result.lines))
    for warning in result.warnings:
        print(f"warning: {warning}")

    args.out.mkdir(parents=True, exist_ok=True)
    hystcomp.save_model(result.model, args.out / "model.json")
    compensator = hystcomp.load_model(args.out / "model.json").inverse()
    export_c(compensator, args.out / "c", prefix="stage")
    print(f"C compensator: {args.out / 'c' / 'stage.h'}, {args.out / 'c' / 'stage.c'}")

    low, high = np.percentile(record.x, [0, 100])
    reference = triangle(low + 0.1 * (high - low), high - 0.1 * (high - low), args.fs)
    v_c = run_c(args.out / "c", reference)
    stepper = compensator.stepper()
    v_python = np.array([stepper.step(x) for x in reference])
    difference = float(np.max(np.abs(v_c - v_python)))
    print(
        f"C against Python on a 1 Hz triangle of {reference.min():.4g} .. {reference.max():.4g} µm "
        f"({reference.size} samples):\n  largest difference {difference:.3g} V "
        f"(voltage {v_c.min():.3g} .. {v_c.max():.3g} V)"
    )
    return {"difference": difference, "v_c": v_c, "v_python": v_python, "result": result}


if __name__ == "__main__":
    main()
