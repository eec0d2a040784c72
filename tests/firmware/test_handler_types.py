"""The command handlers' one typed signature (issue 12: "the handlers get a typed signature (a
Protocol)"), after TMCM-6212 manual 3.1: "Every command consists of a one-byte command field, a
one-byte type field, a one-byte motor/bank field and a four-byte value field."

The command table's handlers (direct mode) are typed by commands.CommandHandler, its program
steps' compilers by steps.Compiler; mypy checks every entry against them (docs/virtual-module.md)."""
import inspect
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from opentmcl.firmware import program
from opentmcl.firmware.table import TABLE
from opentmcl.firmware.vm import VirtualModule

ROOT = Path(__file__).resolve().parents[2]
EMPTY = inspect.Parameter.empty


def _handlers():
    yield from ((f"TABLE[{n}].handler", spec.handler) for n, spec in sorted(TABLE.items()))
    yield from ((f"TABLE[{n}].step", spec.step) for n, spec in sorted(TABLE.items()) if spec.step)
    yield "store_instruction", program.store_instruction
    yield "VirtualModule.store_instruction", VirtualModule.store_instruction


@pytest.mark.parametrize(("name", "handler"), list(_handlers()), ids=lambda v: v if isinstance(v, str) else "")
def test_every_handler_is_annotated(name, handler):
    """Annotated functions are the ones mypy checks (default mode): each field of the request
    (command, type, motor/bank, value) and the result are declared."""
    sig = inspect.signature(handler)
    untyped = [p.name for p in sig.parameters.values() if p.name != "self" and p.annotation is EMPTY]
    assert not untyped, f"{name} ({handler.__qualname__}): parameters without a type: {untyped}"
    assert sig.return_annotation is not EMPTY, f"{name} ({handler.__qualname__}) has no return type"


def test_tables_refuse_a_handler_of_another_signature(tmp_path):
    """A handler without the `program` flag, or a step compiler answering an int, is a type error
    at the table (mypy, as `.ci/run` runs it); one with the right signature is accepted."""
    probe = tmp_path / "probe_handlers.py"
    probe.write_text(textwrap.dedent("""\
        from opentmcl.firmware.commands import Result
        from opentmcl.firmware.effects import Effect
        from opentmcl.firmware.interpreter import Interpreter
        from opentmcl.firmware.table import Spec
        from opentmcl.firmware.vm import VirtualModule
        from opentmcl.protocol.opcodes import COMMANDS


        def cmd_no_flag(vm: VirtualModule, type: int, motor: int, value: int) -> Result:
            return 100, 0


        def cmd_fine(vm: VirtualModule, port: int, bank: int, value: int, program: bool) -> Result:
            return 100, 0


        def step_int(ip: Interpreter, command: int, type: int, motor: int, value: int) -> int:
            return 1
        bad = Spec(COMMANDS[1], cmd_no_flag, Effect.NONE)
        fine = Spec(COMMANDS[1], cmd_fine, Effect.NONE)
        worse = Spec(COMMANDS[1], cmd_fine, Effect.NONE, step=step_int)
        """), encoding="utf-8")
    cache = tmp_path / "cache"  # a cache of its own: a shared one may report a stale path
    run = subprocess.run([sys.executable, "-m", "mypy", "--follow-imports=silent", "--no-error-summary",
                          "--cache-dir", str(cache), str(probe)], cwd=ROOT, capture_output=True, text=True,
                         timeout=300, env={"MYPYPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin"})
    errors = sorted(line.split(":")[1] for line in run.stdout.splitlines()
                    if line.startswith(str(probe)) and ": error:" in line)
    assert errors == ["19", "21"], run.stdout + run.stderr
