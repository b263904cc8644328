"""Files are never lost or mixed: special files and a command's own input are refused, a set
of outputs changes all together or not at all, and an interrupted command cleans up."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp import _signals, presets
from hystcomp.cli import main
from hystcomp.codegen import export_c
from hystcomp.errors import OutputPathError
from hystcomp.experiment import report
from hystcomp.io.atomic import atomic_paths, replace_all
from hystcomp.io.records import read_table, write_table
from tests.codegen.test_codegen import CC, STRICT, needs_cc


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture
def files(tmp_path):
    hystcomp.save_model(presets.paper_pi(), tmp_path / "m.json")
    x = np.linspace(1.0, 30.0, 50)
    write_table(tmp_path / "ref.csv", {"t": np.arange(x.size) / 1e3, "x": x})
    return tmp_path


def _special(kind, path: Path):
    if kind == "fifo":
        os.mkfifo(path)
        return None
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    sock.bind(str(path))
    return sock


def _hidden(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


@pytest.mark.parametrize("kind", ["fifo", "socket"])
@pytest.mark.parametrize("command", ["compensate", "identify", "export-c"])
def test_a_pipe_or_socket_output_is_refused_and_left_alone(files, kind, command):
    out = files / ("comp.h" if command == "export-c" else "out.csv")
    keep = _special(kind, out)
    try:
        if command == "compensate":
            result = run("compensate", files / "m.json", files / "ref.csv", "-o", out)
        elif command == "identify":
            result = run("identify", files / "ref.csv", "--model", "pi", "-o", out)
        else:
            result = run("export-c", files / "m.json", "-o", files, "--prefix", "comp")
        assert result.exit_code == 2, result.output
        assert "device, a pipe or a socket" in result.output
        assert out.is_fifo() if kind == "fifo" else out.is_socket()
        assert not (files / "comp.c").exists()
        assert _hidden(files) == []
    finally:
        if keep is not None:
            keep.close()


@pytest.mark.skipif(not os.path.exists("/dev/null"), reason="no /dev/null")
def test_a_device_output_is_refused(files):
    result = run("compensate", files / "m.json", files / "ref.csv", "-o", "/dev/null")
    assert result.exit_code == 2
    assert "device, a pipe or a socket" in result.output


def test_a_symlink_output_replaces_the_file_it_names_and_stays_a_link(files):
    (files / "real").mkdir()
    target = files / "real" / "v.csv"
    target.write_text("old\n")
    link = files / "v.csv"
    link.symlink_to(target)
    result = run("compensate", files / "m.json", files / "ref.csv", "-o", link)
    assert result.exit_code == 0, result.output
    assert link.is_symlink()
    assert read_table(target, ("v",))["v"].size == 50
    assert _hidden(files) == []
    assert _hidden(files / "real") == []
    dangling = files / "new.csv"
    dangling.symlink_to(files / "real" / "made.csv")
    assert run("compensate", files / "m.json", files / "ref.csv", "-o", dangling).exit_code == 0
    assert dangling.is_symlink()
    assert (files / "real" / "made.csv").is_file()


@pytest.mark.parametrize("suffix", [".h", ".c"])
def test_export_c_refuses_to_overwrite_its_model_file(tmp_path, suffix):
    model = tmp_path / f"comp{suffix}"
    hystcomp.save_model(presets.paper_pi(), model)
    before = model.read_bytes()
    result = run("export-c", model, "-o", tmp_path, "--prefix", "comp")
    assert result.exit_code == 2, result.output
    assert "input file" in result.output
    assert model.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [model.name]
    with pytest.raises(OutputPathError, match="input file"):
        export_c(presets.paper_pi().inverse(), tmp_path, prefix="comp", inputs=(model,))


def _failing_replace(monkeypatch, fail_at, folder=None):
    """os.replace fails at its ``fail_at``-th call (counting renames into ``folder`` only)."""
    real = os.replace
    calls = []

    def replace(src, dst):
        if folder is None or Path(dst).parent == folder:
            calls.append(dst)
        if len(calls) == fail_at:
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", replace)


def test_a_failed_second_rename_puts_the_first_file_back(tmp_path, monkeypatch):
    a, b, c = tmp_path / "a.txt", tmp_path / "b.txt", tmp_path / "c.txt"
    a.write_text("old a")
    b.write_text("old b")  # c did not exist
    _failing_replace(monkeypatch, fail_at=3)  # a, b renamed; c fails

    def write_all(paths):
        with atomic_paths(*paths) as tmps:
            for tmp, text in zip(tmps, ["new a", "new b", "new c"], strict=True):
                tmp.write_text(text)

    with pytest.raises(OutputPathError, match="No space left"):
        write_all((a, b, c))
    monkeypatch.undo()
    assert (a.read_text(), b.read_text()) == ("old a", "old b")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt"]


def test_replace_all_rolls_back_a_file_that_was_new(tmp_path, monkeypatch):
    new_a, new_b = tmp_path / ".na", tmp_path / ".nb"
    new_a.write_text("a")
    new_b.write_text("b")
    _failing_replace(monkeypatch, fail_at=2)
    with pytest.raises(OSError, match="No space"):
        replace_all([(new_a, tmp_path / "a"), (new_b, tmp_path / "b")])
    monkeypatch.undo()
    assert not (tmp_path / "a").exists()
    assert not (tmp_path / "b").exists()


def test_export_c_pair_is_replaced_together(tmp_path, monkeypatch):
    export_c(presets.paper_pi().inverse(), tmp_path, prefix="comp")
    old = [(tmp_path / n).read_text() for n in ("comp.h", "comp.c")]
    _failing_replace(monkeypatch, fail_at=2)  # the .h renamed, the .c fails
    with pytest.raises(OutputPathError):
        export_c(presets.paper_mpi().inverse(), tmp_path, prefix="comp")
    monkeypatch.undo()
    assert [(tmp_path / n).read_text() for n in ("comp.h", "comp.c")] == old
    assert sorted(p.name for p in tmp_path.iterdir()) == ["comp.c", "comp.h"]


class _Comparison:
    pass


def _fake_report(monkeypatch, text):
    monkeypatch.setattr(report, "table1_rows", lambda c: [{"a": text}])
    monkeypatch.setattr(report, "hysteresis_rows", lambda c: [{"b": text}])
    monkeypatch.setattr(report, "report_markdown", lambda c, notes: text)

    def figures(c, out):
        (out / "fig9_compensation.png").write_text(text)
        return {"fig9_compensation.png": None}

    monkeypatch.setattr(report, "write_figures", figures)


def test_compare_folder_changes_all_together_or_not_at_all(tmp_path, monkeypatch):
    out = tmp_path / "out"
    _fake_report(monkeypatch, "first")
    written = report.write_outputs(_Comparison(), out)
    names = sorted(p.name for p in written)
    assert sorted(p.name for p in out.iterdir()) == names
    before = {n: (out / n).read_text() for n in names}

    _fake_report(monkeypatch, "second")
    _failing_replace(monkeypatch, fail_at=3, folder=out)
    with pytest.raises(hystcomp.errors.HystcompError, match="unchanged"):
        report.write_outputs(_Comparison(), out)
    monkeypatch.setattr(os, "replace", _real_replace)
    assert {n: (out / n).read_text() for n in names} == before
    assert sorted(p.name for p in out.iterdir()) == names  # no staging folder left

    def broken(c, out):
        raise hystcomp.errors.InvalidParameterError("no figure")

    monkeypatch.setattr(report, "write_figures", broken)
    with pytest.raises(hystcomp.errors.InvalidParameterError):
        report.write_outputs(_Comparison(), out)
    assert {n: (out / n).read_text() for n in names} == before
    assert sorted(p.name for p in out.iterdir()) == names


_real_replace = os.replace


@needs_cc
def test_a_header_and_source_of_two_exports_do_not_compile_together(tmp_path):
    one, two = tmp_path / "one", tmp_path / "two"
    export_c(presets.paper_pi().inverse(), one, prefix="comp")
    export_c(presets.paper_mpi().inverse(), two, prefix="comp")
    ok = subprocess.run(
        [CC, *STRICT, "-c", "comp.c"], cwd=one, capture_output=True, text=True, check=False
    )
    assert ok.returncode == 0, ok.stderr
    (two / "comp.h").write_text((one / "comp.h").read_text())  # a mixed pair
    mixed = subprocess.run(
        [CC, *STRICT, "-c", "comp.c"], cwd=two, capture_output=True, text=True, check=False
    )
    assert mixed.returncode != 0
    assert "different exports" in mixed.stderr


# A command that stops inside its write (the temporary file exists), as a program does in a
# long kernel where no safe point comes; run as the program (run(): signals and watcher).
STALLED = textwrap.dedent(
    """
    import sys, time
    from hystcomp import _program
    import hystcomp.io.records
    from hystcomp.io import atomic_path
    from hystcomp.cli import compensate

    def stalled_write(path, table, **options):
        with atomic_path(path) as tmp:
            tmp.write_text("half")
            print("writing", flush=True)
            time.sleep(60)

    hystcomp.io.records.write_table = stalled_write
    _program.run()
    """
)


@pytest.mark.parametrize(
    ("sig", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143), (signal.SIGHUP, 129)]
)
def test_a_signal_pending_at_the_commit_replaces_nothing(files, sig, code, monkeypatch):
    """Called as a library: the handler records the signal, the write goes on to its end,
    and the commit refuses it (a signal handler that raised could be swallowed, in a
    callback from C, and the outputs replaced)."""
    out = files / "v.csv"
    out.write_text("old\n")

    def signalled_write(path, table, **options):  # options: write_table's progress
        with hystcomp.io.atomic_path(path) as tmp:
            tmp.write_text("half")
            assert len(_hidden(files)) == 1
            os.kill(os.getpid(), sig)
            time.sleep(0.01)  # the handler runs, and only records it
            tmp.write_text("complete")

    def not_the_command(signum, frame):  # the signal must not reach the test run itself
        raise RuntimeError("the signal reached the test's own handler")

    monkeypatch.setattr("hystcomp.io.records.write_table", signalled_write)
    previous = {s: signal.signal(s, not_the_command) for s in (sig, signal.SIGTERM)}
    try:
        result = run("compensate", files / "m.json", files / "ref.csv", "-o", out)
        assert signal.getsignal(sig) is not_the_command  # restored after the command
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    assert result.exit_code == code, result.output
    assert result.output.splitlines()[-1] == _signals.line(sig)
    assert out.read_text() == "old\n"
    assert _hidden(files) == []


def test_sigterm_to_a_command_stuck_in_a_write_exits_143_and_removes_temporaries(files):
    """No safe point comes (a long kernel, here a sleep): the watcher ends the program."""
    sig, code = signal.SIGTERM, 143
    out = files / "v.csv"
    out.write_text("old\n")
    args = ["compensate", str(files / "m.json"), str(files / "ref.csv"), "-o", str(out)]
    proc = subprocess.Popen(
        [sys.executable, "-c", STALLED, *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout.readline().strip() == "writing"
        assert len(_hidden(files)) == 1  # the temporary beside the output
        time.sleep(0.05)
        start = time.monotonic()
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
        waited = time.monotonic() - start
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == code, err
    assert err == "hystcomp: terminated\n"
    assert waited < _signals.GRACE + 5.0  # not the 60 s of the stalled write
    assert out.read_text() == "old\n"
    assert _hidden(files) == []


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="needs /proc")
def test_a_pipe_named_through_proc_fd_is_refused_before_any_work():
    """``-o /dev/stdout`` in a pipeline: a link to ``pipe:[...]``, which realpath cannot
    follow; the check must still see a pipe, not a new file in /proc/self/fd."""
    from hystcomp.io.atomic import check_output_path

    read, write = os.pipe()
    try:
        with pytest.raises(OutputPathError, match=r"a device, a pipe or a socket"):
            check_output_path(f"/proc/self/fd/{write}", what="model file")
    finally:
        os.close(read)
        os.close(write)


def test_a_full_disk_under_a_nested_atomic_writer_names_the_users_path(tmp_path):
    """A figure writer that writes atomically itself, inside the command's own atomic
    outputs: its failure names the file the user asked for, not a hidden temporary one."""
    from hystcomp.io.atomic import atomic_path

    def save_figure(path):  # as matplotlib's writer behind plot_identification
        with atomic_path(path):
            raise OSError(28, "No space left on device")

    def write():
        with atomic_paths(tmp_path / "model.json", tmp_path / "fig.png") as (_, fig):
            save_figure(fig)

    (tmp_path / "fig.png").write_bytes(b"old")
    with pytest.raises(OutputPathError) as caught:
        write()
    message = str(caught.value)
    assert f"Cannot write {str(tmp_path / 'fig.png')!r}: No space left on device" in message
    assert ".tmp" not in message
    assert (tmp_path / "fig.png").read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png"]
