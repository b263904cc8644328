# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # From a record to C: record, model, compensator, evaluation, firmware
#
# This notebook walks the whole path on the built-in simulated piezo axis (the twin), so it
# runs anywhere: record the stage's answer to an identification signal, identify a
# Modified Prandtl-Ishlinskii (MPI) model, build its compensator, drive the stage with it,
# score the run with `hystcomp.evaluate`, and export the compensator as C99 for a
# controller. With a real stage, replace the two twin runs by your acquisition.
#
# It is a plain Python file in the "percent" format (`# %%` starts a cell): Jupyter opens
# it as a notebook with jupytext, VS Code and Spyder as cells, and `python record_to_c.py`
# runs it.

# %%
import shutil
import subprocess
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import hystcomp
from hystcomp.codegen import export_c
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.io.records import write_table
from hystcomp.plant import Twin

# %% [markdown]
# ## 1. A record
#
# The paper's identification signal (`hystcomp excite mpi`: triangles of 30, 60, 90 and
# 120 V at 1 Hz, 20 kHz) played on the stage; the stage answers with its displacement in
# µm. The record is saved as the CSV a lab would have (`t`, `v`, `x`) and read back.

# %%
t, v = triangle_sequence()
x = Twin(seed=0).run(v)  # with a real stage: your acquisition of the displacement
write_table("record.csv", {"t": t, "v": v, "x": x})
record = hystcomp.read_record("record.csv")
print(
    f"{len(record)} samples at {record.sample_rate:g} Hz, v {record.v.min():g} .. "
    f"{record.v.max():g} V, x {record.x.min():.4g} .. {record.x.max():.4g} µm"
)

# %% [markdown]
# ## 2. A model
#
# The fit chooses its regularisation and its plays' start by the predicted *tracking*, and
# reports that prediction beside a straight line's: the number to read before using the
# compensator.

# %%
model = hystcomp.ModifiedPrandtlIshlinskii().fit(record.v, record.x)
report = model.fit_report_
print(f"fit error: rms {report['rms_error_um']:.3g} µm")
print(
    f"tracking (estimated): rms {report['tracking_rms_um']:.3g} µm, "
    f"straight line {report['baseline_tracking_rms_um']:.3g} µm"
)
hystcomp.save_model(model, "model.json")

# %% [markdown]
# ## 3. The compensator, and a run on the stage
#
# A reference of 1 to 21 µm at 1 Hz; the compensator (the model's analytic inverse, eq. 23
# of the paper) turns it into the voltage to apply, always inside the model's range.

# %%
comp = hystcomp.load_model("model.json").inverse()
t_run = np.arange(40_000) / 20_000  # 2 s at 20 kHz
x_ref = 1.0 + 10.0 * (1.0 - np.cos(2 * np.pi * t_run))
v_run = comp.simulate(x_ref)
x_run = Twin(seed=1).run(v_run)  # with a real stage: play v_run, measure the displacement
print(f"voltage {v_run.min():.3g} .. {v_run.max():.3g} V")

# %% [markdown]
# ## 4. How well did it track?
#
# `hystcomp.evaluate` (the command line's `hystcomp evaluate REFERENCE MEASURED`) matches
# the reference and the measured run by time and gives the paper's figures: rms and largest
# tracking error, and the hysteresis left in % of the range. The first second, where the
# stage leaves its rest, is left out.

# %%
run = hystcomp.evaluate({"t": t_run, "x": x_ref}, {"t": t_run, "x": x_run, "v": v_run}, skip=1.0)
print(
    f"tracking error: rms {run.rms_um:.3f} µm, max {run.max_um:.3f} µm; "
    f"hysteresis {run.hysteresis_pct:.2f} % of the {run.range_um:.3g} µm range"
)

fig, (ax_e, ax_x) = plt.subplots(1, 2, figsize=(10, 3.6))
ax_e.plot(run.t, run.e, lw=0.6)
ax_e.set_xlabel("time t (s)")
ax_e.set_ylabel("error x - x_ref (µm)")
ax_x.plot(run.x_ref, run.x, lw=0.8, label="measured")
ax_x.plot(run.x_ref, run.x_ref, color="0.5", lw=1.2, label="x = x_ref")
ax_x.set_xlabel("reference x_ref (µm)")
ax_x.set_ylabel("displacement x (µm)")
ax_x.legend()
fig.tight_layout()
plt.show()

# %% [markdown]
# ## 5. The compensator as C99
#
# `export_c` writes `stage_x.h` and `stage_x.c`: the identified parameters baked in, no
# allocation, only `<math.h>`. Where a C compiler is at hand, the compiled step is run on
# the same reference and compared with the Python compensator.

# %%
header, source = export_c(comp, "firmware", prefix="stage_x")
print(
    "\n".join(
        line for line in header.read_text().splitlines() if line.startswith(("void", "double"))
    )
)

cc = shutil.which("cc")
if cc is not None:
    driver = Path("firmware/driver.c")
    driver.write_text(
        '#include <stdio.h>\n#include "stage_x.h"\n'
        "int main(void) { stage_x_state s; double x; stage_x_init(&s);\n"
        '  while (scanf("%lf", &x) == 1) printf("%.17g\\n", stage_x_step(&s, x));\n'
        "  return 0; }\n"
    )
    subprocess.run([cc, "-std=c99", "-O2", "-o", "firmware/drive", str(source), str(driver),
                    "-lm"], check=True)  # fmt: skip
    done = subprocess.run(["firmware/drive"], input="\n".join(map(repr, x_ref.tolist())),
                          capture_output=True, text=True, check=True)  # fmt: skip
    v_c = np.array(done.stdout.split(), dtype=float)
    print(f"C against Python: largest difference {np.abs(v_c - v_run).max():.2g} V")
