"""Program read-back and .tmc files in the program view (issue 31 item 3, docs/dashboard-program.md):
the stored program read with command 134 ("read program memory", TMCM-6212 manual 3.6.36) into the
editor, disassembled with labels, with its difference from the editor's program; .tmc files opened
from and saved to the browser. The program is downloaded and checked over a TCP connection of the
same bus, not through the dashboard."""
from __future__ import annotations

import pytest

from .benchkit import TIMEOUT_MS, fresh_page, served, store_program

# TMCM-6212 manual 2.4 "Testing with a simple TMCL program", as the manual prints it.
MANUAL_EXAMPLE = """// A simple example for using TMCL and TMCL-IDE
ROL 0, 500000           //Rotate motor 0 with speed 10000
WAIT TICKS, 0, 500
MST 0
ROR 1, 250000           //Rotate motor 1 with 250000
WAIT TICKS, 0, 500
MST 1
SAP 4, 2, 500000        //Set max. Velocity
SAP 5, 2, 50000         //Set max. Acceleration
Loop:
    MVP ABS, 2, 10000   //Move to Position 10000
    WAIT POS, 2, 0      //Wait until position reached
    MVP ABS, 2, -10000  //Move to Position -10000
    WAIT POS, 2, 0      //Wait until position reached
    JA Loop             //Infinite Loop
"""


@pytest.fixture(scope="module")
def bus():
    with served(("TMCM-6212", 1, None)) as b:
        yield b


@pytest.fixture
def program(browser, bus):
    with fresh_page(browser, bus, view="program") as (page, messages):
        page.wait_for_selector(".CodeMirror", timeout=TIMEOUT_MS)
        yield page, bus.client(1), bus
        assert not messages, messages


def stored(module, count: int) -> list[tuple[int, int, int, int]]:
    """The first `count` program memory locations, read with 134 over TCP."""
    from opentmcl.host.loader import Loader

    return [tuple(i) for i in Loader(module).read(0, count)]


def test_read_back_the_stored_program_into_the_editor(program):
    """A program downloaded by another host (TCP, with 132/133) comes back with Read back: the
    panel tells how it differs from the editor's program (the page's own example), and Open in
    editor puts its disassembly there: with the jump target as a label (Loop is L8 in the module's
    memory) and the bundled names; assembled again it is the same 14 instructions as in memory."""
    from opentmcl.lang import assemble

    page, m, b = program
    prog = assemble(MANUAL_EXAMPLE, module="TMCM-6212")
    store_program(b, prog.instructions)
    page.click("#btn-readback")
    page.wait_for_selector("#readback-summary", timeout=TIMEOUT_MS)
    assert "The module holds 14 instructions" in page.inner_text("#readback-summary")
    assert page.is_visible("#readback-diff") and page.is_visible("#readback-differences")
    page.click("#btn-readback-open")
    text = page.evaluate("OpenTMCL.programEditor.cm.getValue()")
    assert "L8:" in text and "JA L8" in text and "#include tmcm6212.inc" in text
    assert [tuple(i) for i in assemble(text, module="TMCM-6212").instructions] == stored(m, 14)
    page.click("#btn-readback")  # now the editor holds the module's program
    page.wait_for_function("document.getElementById('readback-summary')?.textContent.includes('the same as the editor')",
                           timeout=TIMEOUT_MS)
    assert not page.is_visible("#readback-differences")


def test_read_back_shows_one_changed_instruction(program):
    """The editor's program downloaded from the page, then one value changed in the editor: the
    difference is at address 7, editor line 9 (SAP 5, 2, 50000 against 40000), and the diff marks
    the two lines."""
    page, m, _ = program
    page.evaluate(f"OpenTMCL.programEditor.setSource({MANUAL_EXAMPLE!r})")
    page.click("#btn-download")
    page.wait_for_function("document.getElementById('prog-message').textContent.startsWith('downloaded')", timeout=TIMEOUT_MS)
    assert stored(m, 8)[7] == (5, 5, 2, 50000)
    page.evaluate("OpenTMCL.programEditor.setSource(OpenTMCL.programEditor.cm.getValue().replace('SAP 5, 2, 50000', 'SAP 5, 2, 40000'))")
    page.click("#btn-readback")
    page.wait_for_selector("#readback-differences", timeout=TIMEOUT_MS)
    rows = page.eval_on_selector_all("#readback-differences tr", "rs => rs.slice(1).map(r => [...r.cells].map(c => c.textContent))")
    assert rows == [["7", "9", "SAP 5, 2, 40000", "SAP 5, 2, 50000"]]
    diff = page.inner_text("#readback-diff")
    assert "-    SAP APMaxAcceleration, Motor2, 40000" in diff and "+    SAP APMaxAcceleration, Motor2, 50000" in diff


def test_open_and_save_tmc_files_in_the_browser(program, tmp_path):
    """Open .tmc reads a file chosen in the browser into the editor; Save .tmc hands the editor's
    text to the browser as a download named after the module. No path on the dashboard's machine
    is involved (docs/dashboard.md "Threat model")."""
    page, _, _ = program
    path = tmp_path / "example.tmc"
    path.write_text(MANUAL_EXAMPLE)
    page.set_input_files("#prog-open", str(path))
    page.wait_for_function("OpenTMCL.programEditor.cm.getValue().startsWith('// A simple example')", timeout=TIMEOUT_MS)
    page.evaluate("OpenTMCL.programEditor.setSource(OpenTMCL.programEditor.cm.getValue() + '// saved\\n')")
    with page.expect_download(timeout=TIMEOUT_MS) as info:
        page.click("#btn-save")
    download = info.value
    assert download.suggested_filename == "TMCM-6212.tmc"
    saved = tmp_path / "saved.tmc"
    download.save_as(str(saved))
    assert saved.read_text() == MANUAL_EXAMPLE + "// saved\n"
