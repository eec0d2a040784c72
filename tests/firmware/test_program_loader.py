"""Loader and debugger over a client connection (TMCM-6212 manual 3.6.36 Table 13: 128-135 are
"used by the TMCL-IDE (in order to implement e.g. the debugging functions ...)")."""
from __future__ import annotations

import pytest

from opentmcl.host import TmclStatusError, connect
from opentmcl.host.debugger import DebugError, Debugger, parse_watch, parse_watches
from opentmcl.host.loader import Loader, LoaderError, VerifyError, instructions_of
from opentmcl.lang.assembler import AsmError, assemble
from opentmcl.lang.binfile import Instruction

SRC = """
    SGP 5, 2, 0
Loop:
    GGP 5, 2
    CALC ADD, 1
    AGP 5, 2
    COMP 3
    JC LT, Loop
    WAIT TICKS, 0, 10
    CALCX LOAD
    STOP
"""


@pytest.fixture
def target():
    module = connect("sim://TMCM-6212")
    yield module, module.client.transport.module
    module.client.close()


def test_download_verify_and_read_back(target):
    """132 <start>, the instructions (status 101), 133, then 134 at every address gives them back."""
    module, vm = target
    prog = assemble(SRC, module="TMCM-6212")
    loader = Loader(module)
    written = loader.download(prog, start=10)
    assert written == prog.instructions
    assert loader.read(10, len(written)) == written
    assert vm.program.code[10] == tuple(written[0])
    assert loader.read_one(0) == Instruction(0, 0, 0, 0)


def test_a_program_assembled_for_its_load_address_runs_there(target, tmp_path, capsys):
    """3.6.36 command 132 "enter download mode" at a start address, 129 type 1 "start from the
    given address": the loop's JC (3.6.15) must target the loop where it lies, so source loaded at
    address 10 is assembled for 10 (the loop counts user variable 5 up to 3, then X = A)."""
    module, vm = target
    prog = assemble(SRC, module="TMCM-6212", origin=10)
    assert prog.labels["Loop"] == 11 and prog.instructions[5].value == 11
    assert prog.listing().splitlines()[0].startswith("0010 ")
    loader = Loader(module)
    loader.download(prog, start=10)
    loader.run(10)
    vm.advance(1.0)
    assert module.request(10, 5, 2).value == 3       # GGP 5, 2: the loop ran three times
    assert module.request(10, 130, 0).value == 18    # GP130 program counter: on the STOP
    with pytest.raises(ValueError):
        assemble(SRC, origin=-1)
    with pytest.raises(AsmError, match="from address 6140"):
        assemble(SRC, module="TMCM-6212", origin=6140)


def test_binary_image_and_tuples_are_accepted(target):
    module, _ = target
    prog = assemble(SRC, module="TMCM-6212")
    assert instructions_of(prog.image()) == prog.instructions
    assert instructions_of([(22, 0, 0, 0)]) == [Instruction(22, 0, 0, 0)]
    with pytest.raises(LoaderError):
        instructions_of([(1, 2)])


def test_verify_reports_the_first_difference(target):
    module, vm = target
    loader = Loader(module)
    code = loader.download(assemble(SRC, module="TMCM-6212"))
    vm.program.code[3] = (28, 0, 0, 0)
    with pytest.raises(VerifyError) as err:
        loader.verify(code)
    assert err.value.mismatches[0][0] == 3 and "address 3" in str(err.value)


def test_refused_instruction_and_protected_read(target):
    """A download past the end of program memory is refused (status 4); with GP81 = 1 ("protection
    against disassembling") 134 is refused."""
    module, vm = target
    loader = Loader(module)
    with pytest.raises(LoaderError, match="refused"):
        loader.download([(22, 0, 0, 0)] * 2, start=vm.profile.program_memory - 1)
    module.set_global(81, 1)
    with pytest.raises(TmclStatusError):
        loader.read_one(0)


def test_application_control_and_status(target):
    """129 run, 128 stop, 130 step, 131 reset and 135 (mode, wait flag, PC, A, X, flags)."""
    module, _ = target
    loader = Loader(module)
    loader.download(assemble(SRC, module="TMCM-6212"))
    loader.run(0)
    module.client.sleep(0.05)
    st = loader.status()
    assert (st.mode_name, st.waiting, st.pc, st.accumulator) == ("run", True, 6, 3)
    assert loader.variable(5) == 3
    st = loader.wait_stopped(1.0)
    assert (st.mode_name, st.pc, st.x_register) == ("stop", 8, 3)
    loader.reset()
    assert loader.status().mode_name == "reset"
    loader.step()
    assert loader.status().pc == 1 and loader.status().mode_name == "step"


def test_debugger_breakpoints_until_and_watches(target):
    """TMCM-6212 3.6.15 COMP: "The internal arithmetic status flags are set according to the result
    of the comparison" - 135 lists only types 0-3 (3.6.36 Table 13), so no request reads them; the
    `flags` watch of a sim:// module reads them in-process: LT while var5 < 3, EQ once it is 3."""
    module, _ = target
    prog = assemble(SRC, module="TMCM-6212")
    loader = Loader(module)
    loader.download(prog)
    loader.reset()
    dbg = Debugger(loader, prog.instructions, prog.labels, prog.source,
                   watches=parse_watches("a, var5, pc, flags"))
    dbg.breakpoints.add(dbg.address("Loop"))
    st = dbg.cont()
    assert st.pc == 1 and st.mode == 2
    st = dbg.cont()                                     # once round the loop
    assert st.pc == 1 and dict(dbg.watch_values())["var5"] == 1
    assert "LT" in dict(dbg.watch_values())["flags"].split()     # COMP 3 with A = 1
    assert dbg.until("7").pc == 1                       # a breakpoint on the way stops `until` too
    dbg.breakpoints.clear()
    st = dbg.until("7")                                 # through the WAIT (waited out) to CALCX
    assert st.pc == 7 and st.accumulator == 3
    flags = dict(dbg.watch_values())["flags"].split()  # COMP 3 with A = 3, nothing since
    assert "EQ" in flags and "LT" not in flags and "GT" not in flags
    st = dbg.cont()
    assert st.mode == 0 and st.pc == 8 and st.x_register == 3
    assert dbg.where(3) == "Loop+2" and "CALC ADD, 1" in dbg.line(2)


def test_watch_expressions():
    assert [w.name for w in parse_watches("a x pc flags state var3 out0 in1 adc2 pos0 target1 speed2 "
                                          "ap4.1 gp66 gp3.2")] == [
        "a", "x", "pc", "flags", "state", "var3", "out0", "in1", "adc2", "pos0", "target1", "speed2",
        "ap4.1", "gp66", "gp3.2"]
    with pytest.raises(DebugError):
        parse_watch("nonsense")
