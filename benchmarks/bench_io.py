"""Speed and peak memory of writing and reading a long CSV record (t, v, x).

Each step runs in a fresh process that reads the same table from a raw file (in place, no
temporaries) and measures its own wall time and peak resident memory (``VmHWM``, Linux);
memory is given as the growth over a process that only imports (and, for writing, reads the
table). Writing, the former writer, reading and ``numpy.loadtxt`` run twice, alternating,
and the faster run counts (the machine may be shared). The references run in the same
benchmark on the same array and file:

* writing: :func:`numpy.savetxt` with ``%.17g`` (numpy's writer at round-trip precision),
  and the former writer (a list of every value's ``repr``, joined; on a tenth of the
  samples, as it needs about 400 bytes a sample, and scaled per sample);
* reading: :func:`numpy.loadtxt` of the same file (the whole table at once).

Targets: writing in under 1 GB and at least 5x faster per sample than the former writer;
reading in less than 4x the memory of the values and at least 1.5x faster than
``numpy.loadtxt`` (the compiled parser of ``hystcomp.io._floatparse``; numpy's own parser
alone read at 0.7x). Timings on a shared machine are noisy:
read the ratios, which come from one run.

Run alone with ``python benchmarks/bench_io.py``; ``BENCH_IO_SAMPLES`` sets the length
(default 1e7).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

import numpy as np

SAMPLES = int(float(os.environ.get("BENCH_IO_SAMPLES", "1e7")))

_SETUP = """
import resource, sys, time
import numpy as np
from hystcomp.io.records import read_record, write_table
n, path, source, size = int(sys.argv[1]), sys.argv[2], sys.argv[3], int(sys.argv[4])
def peak():  # MB; VmHWM, as ru_maxrss keeps the parent's peak across fork and exec
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
def table():
    data = np.empty((3, n))  # the same array in every step, read in place (no temporaries)
    with open(source, "rb") as f:
        for row in data:
            f.readinto(memoryview(row).cast("B"))
            f.seek(8 * (size - n), 1)
    return {"t": data[0], "v": data[1], "x": data[2]}
"""

_STEPS = {
    "baseline": "cols = table(); start = time.perf_counter()\n",
    "imports": "start = time.perf_counter()\n",
    "write": "cols = table(); base = peak(); start = time.perf_counter()\n"
    "write_table(path, cols)\n",
    "savetxt": "cols = table(); base = peak(); start = time.perf_counter()\n"
    "np.savetxt(path, np.column_stack(list(cols.values())), fmt='%.17g', delimiter=',',"
    " header='t,v,x', comments='')\n",
    "former": "cols = table(); base = peak(); start = time.perf_counter()\n"
    "rows = np.column_stack(list(cols.values())).tolist()\n"
    "text = '\\n'.join(['t,v,x', *(','.join(map(repr, row)) for row in rows)]) + '\\n'\n"
    "open(path, 'w').write(text)\n",
    "read": "base = peak(); start = time.perf_counter()\nrec = read_record(path)\n",
    "loadtxt": "base = peak(); start = time.perf_counter()\n"
    "data = np.loadtxt(path, delimiter=',', skiprows=1)\n",
}


def _step(name: str, n: int, path: str, source: str) -> tuple[float, float]:
    """Seconds and peak memory (MB, the whole process) of one step in a fresh process."""
    code = _SETUP + _STEPS[name] + "print(time.perf_counter() - start, peak())\n"
    out = subprocess.run(
        [sys.executable, "-c", code, str(n), path, source, str(SAMPLES)],
        capture_output=True,
        text=True,
        check=True,
    )
    seconds, mb = map(float, out.stdout.split())
    return seconds, mb


def _row(name, value, unit, target=None, ok=None) -> dict:
    return {"name": name, "value": value, "unit": unit, "target": target, "ok": ok}


def run() -> list[dict]:
    """Measure and return one row per figure: name, value, unit, target, ok."""
    n = SAMPLES
    label = f"{n:.0e}-sample CSV"
    values_mb = 3 * 8 * n / 2**20
    with tempfile.TemporaryDirectory() as folder:
        source = f"{folder}/table.f8"
        t = np.arange(n) / 2e4
        rng = np.random.default_rng(0)
        v = 60 + 50 * np.sin(t) + rng.standard_normal(n)
        np.vstack([t, v, 12 * np.cos(t) + 0.01 * rng.standard_normal(n)]).tofile(source)
        del t, v
        ours, theirs = f"{folder}/ours.csv", f"{folder}/savetxt.csv"
        _, base_mb = _step("baseline", n, ours, source)  # imports and the table
        _, imports_mb = _step("imports", n, ours, source)
        best = {}
        for _ in range(2):  # the faster of two runs, alternating, against a busy machine
            for name in ("write", "former", "read", "loadtxt"):
                length = n // 10 if name == "former" else n
                out = f"{folder}/former.csv" if name == "former" else ours
                seconds, mb = _step(name, length, out, source)
                old = best.get(name, (float("inf"), 0.0))
                best[name] = (min(seconds, old[0]), max(mb, old[1]))
        savetxt_s, savetxt_mb = _step("savetxt", n, theirs, source)
        former_s, former_mb = best["former"]
        former_s *= 10  # per sample, at the full length
    (write_s, write_mb), (read_s, read_mb), (loadtxt_s, loadtxt_mb) = (
        best["write"],
        best["read"],
        best["loadtxt"],
    )
    write_mb, savetxt_mb = write_mb - base_mb, savetxt_mb - base_mb
    read_mb, loadtxt_mb = read_mb - imports_mb, loadtxt_mb - imports_mb
    # the former writer ran on a tenth of the table: its growth over the loaded table, x10
    former_mb = 10 * (former_mb - base_mb)
    speedup = former_s / write_s
    return [
        _row(f"write {label}: write_table", write_s, "s"),
        _row(
            f"write {label}: write_table peak memory growth",
            write_mb,
            "MB",
            "< 1024",
            write_mb < 1024,
        ),
        _row(f"write {label}: numpy.savetxt %.17g", savetxt_s, "s"),
        _row(f"write {label}: numpy.savetxt peak memory growth", savetxt_mb, "MB"),
        _row("write: numpy.savetxt time / write_table time", savetxt_s / write_s, "x"),
        _row("write: former writer (repr list, 1/10 length) time, scaled", former_s, "s"),
        _row("write: former writer (1/10 length) peak memory growth, x10", former_mb, "MB"),
        _row("write: former writer time / write_table time", speedup, "x", ">= 5", speedup >= 5),
        _row(f"read {label}: read_record", read_s, "s"),
        _row(
            f"read {label}: read_record peak memory growth / values ({values_mb:.0f} MB)",
            read_mb / values_mb,
            "x",
            "< 4",
            read_mb / values_mb < 4,
        ),
        _row(f"read {label}: numpy.loadtxt", loadtxt_s, "s"),
        _row(
            f"read {label}: numpy.loadtxt peak memory growth / values",
            loadtxt_mb / values_mb,
            "x",
        ),
        _row(
            "read: numpy.loadtxt time / read_record time",
            loadtxt_s / read_s,
            "x",
            ">= 1.5",
            loadtxt_s / read_s >= 1.5,
        ),
    ]


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']}: {row['value']:.4g} {row['unit']}")
