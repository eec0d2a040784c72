"""`opentmcl debug` driven through a real pseudo-terminal, as a user at a terminal would
(TMCM-6212 manual 3.6.36: 130 step, 135 status, 128/129/131; breakpoints and "run to label"
host-side)."""
from __future__ import annotations

import os
import re
import select
import signal
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals need POSIX")

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
PROMPT = b"(tmcl) "
HANG_GUARD = 60.0  # seconds without any output before the test gives up (not a speed limit)


STARTED: list[subprocess.Popen] = []


@pytest.fixture(autouse=True)
def no_leftover_debuggers():
    """A test that fails half-way must not leave its debugger (maybe running a program) behind."""
    yield
    while STARTED:
        proc = STARTED.pop()
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=HANG_GUARD)


class Terminal:
    def __init__(self, *args: str):
        self.master, slave = os.openpty()
        env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), TERM="dumb")
        self.proc = subprocess.Popen([sys.executable, "-m", "opentmcl", *args], stdin=slave, stdout=slave,
                                     stderr=slave, cwd=ROOT, env=env, close_fds=True, start_new_session=True)
        STARTED.append(self.proc)
        os.close(slave)
        self.buf = b""

    def read_until(self, marker: bytes) -> str:
        while marker not in self.buf:
            ready, _, _ = select.select([self.master], [], [], HANG_GUARD)
            assert ready, f"no output; so far: {self.buf[-500:]!r}"
            try:
                chunk = os.read(self.master, 4096)
            except OSError:  # the child closed the terminal
                chunk = b""
            assert chunk, f"terminal closed; so far: {self.buf[-500:]!r}"
            self.buf += chunk
        out, _, self.buf = self.buf.partition(marker)
        return out.decode(errors="replace").replace("\r", "")

    def command(self, line: str) -> str:
        os.write(self.master, line.encode() + b"\n")
        return self.read_until(PROMPT)

    def close(self) -> int:
        try:
            os.write(self.master, b"quit\n")
            return self.proc.wait(timeout=HANG_GUARD)
        finally:
            os.close(self.master)


@pytest.fixture
def timer_session():
    term = Terminal("debug", str(EXAMPLES / "tmcm6212_3.5.6.4_timer_interrupt.tmc"))
    banner = term.read_until(PROMPT)
    assert "loaded 16 instructions" in banner and "verified" in banner
    yield term
    assert term.close() == 0


def test_breakpoint_in_the_timer_handler_and_watches(timer_session):
    """Breakpoint at the handler label: `cont` single-steps (130) until the PC reaches it, i.e.
    after timer 0 fired (3.5.6.4: period 1000 ms); the watches show OUT0/OUT3."""
    t = timer_session
    assert "breakpoint at 9 Timer0Irq" in t.command("break Timer0Irq")
    out = t.command("watch out0 out3 pc")
    assert re.search(r"out0 = 0", out)
    out = t.command("cont")
    assert "[paused]" in out and "PC=9" in out and "GIO 0, 2" in out
    out = t.command("step 3")           # GIO, JC NZ (not taken), SIO 0, 2, 1
    assert "PC=12" in out and "out0 = 1" in out and "RETI" in out
    out = t.command("step")             # RETI: back to the interrupted main program
    assert "PC=12" not in out
    assert re.search(r"PC=[5-8]\b", out)


def test_run_to_label_step_and_registers(timer_session):
    """`until Loop` runs to the label (a temporary breakpoint); `info` shows A, X, PC and flags;
    `reset` (131) zeroes PC and registers."""
    t = timer_session
    out = t.command("until Loop")
    assert "PC=4" in out and "Loop" in out
    out = t.command("step")             # SIO 3, 2, 1
    assert "PC=5" in out
    out = t.command("watch out3")
    assert "out3 = 1" in out
    out = t.command("list")
    assert re.search(r"^>\s+5\s+Loop\+1\s+WAIT TICKS, 0, 50", out, re.M)
    out = t.command("reset")
    assert "[reset]" in out and "PC=0" in out and "A=0 X=0" in out


def test_bad_input_is_an_error_message_not_a_traceback(timer_session):
    """Bad input: clear messages, the session goes on."""
    t = timer_session
    assert "no label 'Nowhere'" in t.command("break Nowhere")
    assert "cannot watch" in t.command("watch bogus")
    assert "unknown command" in t.command("frobnicate")
    assert "error" in t.command("sleep -1")
    assert "Traceback" not in t.buf.decode(errors="replace")
    assert "PC=" in t.command("info")


def test_variables_program_runs_to_stop():
    """7.4 example under the debugger: `cont` without breakpoints runs to the STOP; var42 = 2468."""
    t = Terminal("debug", str(EXAMPLES / "tmcm6212_7.4_user_variables.tmc"), "-w", "var42")
    t.read_until(PROMPT)
    out = t.command("cont")
    assert "[stopped]" in out and "var42 = 2468" in out and "STOP" in out
    out = t.command("set var 42 5")
    assert t.command("info").count("var42 = 5") == 1
    assert t.close() == 0


def test_ctrl_c_stops_a_free_run(tmp_path):
    """A program that never stops: `cont` runs it freely until the user presses Ctrl-C (SIGINT),
    which stops it (128) and returns to the prompt."""
    src = tmp_path / "forever.tmc"
    src.write_text("Loop: CALC ADD, 1\n  JA Loop\n")
    t = Terminal("debug", str(src))
    t.read_until(PROMPT)
    os.write(t.master, b"cont\n")
    t.read_until(b"(Ctrl-C stops)")
    t.proc.send_signal(signal.SIGINT)
    out = t.read_until(PROMPT)
    assert "interrupted; program stopped" in out and "[stopped]" in out
    assert t.close() == 0


def test_help_lists_every_command_and_no_undocumented_one():
    """Issue 32 item 7: "The debugger's help lists "Undocumented commands: EOF"". End of input
    (Ctrl-D) is no command to type: `help` lists only documented commands, `print` among them, and
    `help quit` says that Ctrl-D leaves too -- which it does, with status 0."""
    t = Terminal("debug", str(EXAMPLES / "tmcm6212_7.4_user_variables.tmc"))
    t.read_until(PROMPT)
    out = t.command("help")
    assert "Documented commands" in out and "Undocumented" not in out and "EOF" not in out
    listed = set(out.split("=\n", 1)[1].split())
    assert {"print", "p", "quit", "step", "cont", "break", "watch", "info"} <= listed
    assert "Ctrl-D" in t.command("help quit")
    os.write(t.master, b"\x04")                       # Ctrl-D at the prompt: end of input
    assert t.proc.wait(timeout=HANG_GUARD) == 0
    os.close(t.master)


MOVE = """\
    SAP 4, 0, 1000        // maximum positioning speed (TMCM-6212 manual 4.1, AP 4)
    SGP 0, 3, 500         // timer 0 period (manual 5.1, bank 3)
    SGP 42, 2, 21         // user variable 42
    MVP ABS, 0, 5000
    WAIT POS, 0, 0
    STOP
"""


def test_print_reads_registers_variables_and_parameters_by_number_or_name(tmp_path):
    """Issue 32 item 7: "no way to print an expression or a parameter by name". After the program
    ran to its STOP: axis parameters by our name, the manual's number (AP1, ap1.0), PyTrinamic's
    name, NAME.M for another motor; a global parameter by name; expressions in the assembler's
    syntax (precedence, C division) over A, user variables and parameters."""
    src = tmp_path / "move.tmc"
    src.write_text(MOVE)
    t = Terminal("debug", str(src))
    t.read_until(PROMPT)
    assert "[stopped]" in t.command("cont")
    for line, shown in [("print actual_position", "actual_position = 5000"),
                        ("print AP1", "AP1 = 5000"),
                        ("p ap1.0 - target0", "ap1.0 - target0 = 0"),
                        ("print MaxVelocity", "MaxVelocity = 1000"),
                        ("print actual_position.1", "actual_position.1 = 0"),
                        ("print timer_0", "timer_0 = 500"),
                        ("print var42", "var42 = 21"),
                        ("print var42 * 2 + a", "var42 * 2 + a = 42"),       # A: 0, nothing loaded it
                        ("print (var42 + 1) * -7 / 4", "(var42 + 1) * -7 / 4 = -38"),   # -38.5 truncated
                        ("print state", "state = stop")]:
        assert t.command(line).strip().splitlines()[-1] == shown, line   # after the echoed input
    assert t.close() == 0


def test_print_explains_what_it_cannot_print(timer_session):
    """Bad input to `print`: one error line each, the session goes on."""
    t = timer_session
    assert "cannot print 'bogus': no register, variable or parameter of TMCM-6212" in t.command("print bogus")
    assert "did you mean actual_position" in t.command("print actual_positon")
    assert "division by zero" in t.command("print 1/0")
    assert "expression ends too early" in t.command("print a +")
    assert "flags is text" in t.command("print flags + 1")
    assert "timer_0 is a global parameter" in t.command("print timer_0.1")
    assert "usage: print EXPR" in t.command("print")
    assert "Traceback" not in t.buf.decode(errors="replace")
    assert "PC=" in t.command("info")
