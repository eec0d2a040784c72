"""The program view's editor (CodeMirror 5, static/editor.js) in headless Chromium against a
virtual TMCM-6212: highlighting, every diagnostic marked at once, breakpoints and stepping.

What the editor shows is checked in the DOM; what the module does is checked over the wire
(command 135 "Get application status" and GGP through the dashboard's client, manual 3.6.36).
"""
from __future__ import annotations

from pathlib import Path

from opentmcl.protocol import opcodes

from .conftest import ARTIFACTS

TIMEOUT_MS = 60000  # only a guard against hanging: the tests wait for a state, they do not time anything
EXAMPLES = Path(__file__).resolve().parents[1] / "lang" / "examples"


def open_program(page, source: str) -> None:
    """Open the program view and put `source` into the editor."""
    page.click("#views-nav a[data-view='program']")
    page.wait_for_selector("#program-editor .CodeMirror", state="visible", timeout=TIMEOUT_MS)
    page.evaluate("src => OpenTMCL.programEditor.setSource(src)", source)


def texts(page, selector: str) -> list[str]:
    return page.eval_on_selector_all(selector, "els => els.map(e => e.textContent)")


def download(page) -> None:
    page.click("#btn-download")
    page.wait_for_function("document.getElementById('prog-message').textContent.startsWith('downloaded')",
                           timeout=TIMEOUT_MS)


def current_lines(page) -> list[int]:
    """1-based numbers of the lines the editor highlights as the current one."""
    return page.evaluate("""() => { const cm = OpenTMCL.programEditor.cm, out = [];
        cm.eachLine(h => { if ((cm.lineInfo(h).bgClass || '').includes('current-line')) out.push(cm.getLineNumber(h) + 1); });
        return out; }""")


def test_manual_example_is_highlighted_by_kind(page):
    """TMCM-6212 manual 3.5.6.4, the timer interrupt program with "#include Interrupts.inc":
    mnemonics, the WAIT type TICKS, the JC condition NZ, labels, the directive, numbers and the
    "//" comments each get their own class."""
    source = (EXAMPLES / "tmcm6212_3_5_6_4_timer_interrupt_inc.tmc").read_text()
    open_program(page, source)
    page.wait_for_selector("#program-editor .cm-keyword", timeout=TIMEOUT_MS)
    keywords = texts(page, "#program-editor .cm-keyword")
    assert {"VECT", "SGP", "EI", "SIO", "WAIT", "JA", "GIO", "JC", "RETI"} <= set(keywords)
    assert "TICKS" in texts(page, "#program-editor .cm-atom")
    assert texts(page, "#program-editor .cm-builtin") == ["NZ"]       # JC NZ, Out0Off
    assert {"Loop", "Timer0Irq", "Out0Off"} <= set(texts(page, "#program-editor .cm-def"))
    assert texts(page, "#program-editor .cm-meta") == ["#include"]
    assert "Interrupts.inc" in texts(page, "#program-editor .cm-string")
    assert {"1000", "50", "3", "2", "1", "0"} <= set(texts(page, "#program-editor .cm-number"))
    comments = texts(page, "#program-editor .cm-comment")
    assert "//check if OUT0 is high" in comments and len(comments) == source.count("//")
    assert "Timer0Irq" in texts(page, "#program-editor .cm-variable")  # VECT TI_TIMER0, Timer0Irq
    page.screenshot(path=str(ARTIFACTS / "editor-highlighting.png"), full_page=True)


def test_the_editor_knows_the_assemblers_words(page):
    """The highlighted vocabulary is the assembler's: every mnemonic (TMCM-6212 3.4.1, PD28-1021
    3.5), every symbolic type operand and the JC conditions (3.6.16), so the two cannot drift."""
    open_program(page, "")
    words = page.evaluate("OpenTMCL.programEditor.words")
    mnemonics = {c.mnemonic for c in opcodes.COMMANDS.values() if c.mnemonic}
    assert set(words["mnemonics"]) == mnemonics | {"RAW"}
    types = {name for key, table in opcodes.SYMBOL_TABLES.items() if key != "jc" for name in table}
    assert set(words["types"]) == types
    assert set(words["conditions"]) == set(opcodes.JC_CONDITIONS)


def test_three_errors_show_three_marks_and_a_warning(page):
    """Issue 15 item 6: every error of a source is reported in one run; each is marked at its line
    and column (gutter, underline, message on hover) and listed below. With the module known,
    "ROR 7, 1000" (the TMCM-6212 has six motors, manual 1 "Features") is a warning."""
    source = "    ROR 7, 1000\n    FOO 1\n    MVP ABS, 0, 1 +\n    JA Nowhere\n"
    open_program(page, source)
    page.click("#btn-assemble")
    page.wait_for_selector("#asm-errors .asm-error", timeout=TIMEOUT_MS)
    assert page.locator("#program-editor .asm-mark.error").count() == 3
    assert page.locator("#program-editor .asm-mark.warning").count() == 1
    marks = page.eval_on_selector_all("#program-editor .cm-asm-error",
                                      "els => [...new Set(els.map(e => e.dataset.diagnostic))]")
    assert len(marks) == 3
    underlined = texts(page, "#program-editor .cm-asm-error")
    assert underlined == ["FOO", "Nowhere"] or set(underlined) >= {"FOO", "Nowhere"}
    titles = page.eval_on_selector_all("#program-editor .cm-asm-error", "els => els.map(e => e.title)")
    assert "unknown mnemonic 'FOO'" in titles and "undefined symbol 'Nowhere'" in titles
    warned = page.eval_on_selector_all("#program-editor .cm-asm-warning", "els => els.map(e => e.textContent + '|' + e.title)")
    assert warned == ["7|ROR: motor 7 does not exist on TMCM-6212 (motors 0..5)"]
    listed = texts(page, "#asm-errors > div")
    assert [row.split(":")[0] for row in listed] == ["line 1, column 9", "line 2, column 5",
                                                     "line 3, column 20", "line 4, column 8"]
    assert "3 errors, 1 warning" in page.inner_text("#prog-message")
    page.screenshot(path=str(ARTIFACTS / "editor-diagnostics.png"), full_page=True)


def test_fixing_the_source_clears_the_marks(page, served):
    """After a clean assembly no mark is left, and the program downloads (132/133, manual 3.6.36)."""
    open_program(page, "    FOO 1\n")
    page.click("#btn-assemble")
    page.wait_for_selector("#program-editor .asm-mark.error", timeout=TIMEOUT_MS)
    page.evaluate("OpenTMCL.programEditor.setSource('    CALC LOAD, 3\\n    STOP\\n')")
    download(page)
    assert page.locator("#program-editor .asm-mark").count() == 0
    assert page.locator("#program-editor .cm-asm-error").count() == 0
    assert served.dashboard.program is not None and len(served.dashboard.program.instructions) == 3


def test_typing_into_the_editor_edits_the_program(page, served):
    """The editor is a real text field: what is typed is what is assembled and downloaded."""
    open_program(page, "")
    page.click("#program-editor .CodeMirror-lines")
    page.keyboard.type("CALC LOAD, 42\n")
    download(page)
    assert [tuple(i) for i in served.dashboard.program.instructions][:1] == [(19, 9, 0, 42)]


def test_download_and_step_program(page, served):
    """Manual 3.6.36: 132/133 download, 130 executes one instruction, 135 reports the program counter.
    Stepping highlights the next line and shows A (manual 3.6.26 CALC LOAD puts the value into A);
    AGP 3, 2 stores A in user variable 3 (manual 3.6.28), read back with GGP 3, 2."""
    open_program(page, "    CALC LOAD, 5\n    CALC ADD, 2\n    AGP 3, 2\n    STOP\n")
    download(page)
    page.click("#btn-step")
    page.wait_for_function("document.getElementById('prog-pc').textContent === '1'", timeout=TIMEOUT_MS)
    page.wait_for_function("OpenTMCL.programEditor.currentLine() === 2", timeout=TIMEOUT_MS)
    assert current_lines(page) == [2]
    assert page.inner_text("#prog-a") == "5"
    assert served.dashboard.program_state()["pc"] == 1          # 135 over the wire
    page.click("#btn-step")
    page.click("#btn-step")
    page.wait_for_function("document.getElementById('prog-pc').textContent === '3'", timeout=TIMEOUT_MS)
    page.wait_for_function("document.getElementById('prog-var-3') && "
                           "document.getElementById('prog-var-3').textContent === '7'", timeout=TIMEOUT_MS)
    assert current_lines(page) == [4]
    assert served.dashboard.module.reply(10, 3, 2).value == 7    # GGP 3, 2
    page.screenshot(path=str(ARTIFACTS / "dashboard-program.png"), full_page=True)


def test_run_stops_at_breakpoint(page, served):
    """Host-side breakpoints (docs/dashboard-program.md): clicking a line number sets one; Run
    single-steps (manual 3.6.36 command 130) until the program counter reaches the line; the
    accumulator counts the passes of the loop (manual 3.6.26 CALC ADD)."""
    open_program(page, "    CALC LOAD, 0\nLoop:\n    CALC ADD, 1\n    JA Loop\n")
    download(page)
    page.locator("#program-editor .CodeMirror-linenumber", has_text="3").first.click()
    page.wait_for_selector("#gutter-3.bp", timeout=TIMEOUT_MS)
    page.wait_for_function("window.fetch('api/program').then(r => r.json())"
                           ".then(j => j.state.breakpoints.length === 1)", timeout=TIMEOUT_MS)
    page.click("#btn-run")  # from address 0: CALC LOAD runs, then the PC is at the breakpoint
    page.wait_for_function("document.getElementById('prog-line').textContent === '3' && "
                           "document.getElementById('prog-a').textContent === '0'", timeout=TIMEOUT_MS)
    page.wait_for_function("OpenTMCL.programEditor.currentLine() === 3", timeout=TIMEOUT_MS)
    st = served.dashboard.program_state()
    assert st["pc"] == 1 and st["a"] == 0 and st["mode"] != 1
    page.click("#btn-run")  # once round the loop: CALC ADD, JA, back at the breakpoint
    page.wait_for_function("document.getElementById('prog-line').textContent === '3' && "
                           "document.getElementById('prog-a').textContent === '1'", timeout=TIMEOUT_MS)
    st = served.dashboard.program_state()
    assert st["pc"] == 1 and st["a"] == 1 and st["mode"] != 1
    page.wait_for_timeout(500)  # a late answer of the run request must not move the highlight
    assert current_lines(page) == [3] and page.inner_text("#prog-line") == "3"
    page.click("#gutter-3")  # the breakpoint gutter clears it again
    page.wait_for_function("window.fetch('api/program').then(r => r.json())"
                           ".then(j => j.state.breakpoints.length === 0)", timeout=TIMEOUT_MS)


def _user_variable(served, n: int, want: int) -> None:
    """Until GGP n, 2 (over the dashboard's link) reads `want` (bounded)."""
    import time

    deadline = time.monotonic() + TIMEOUT_MS / 1000
    while served.dashboard.module.reply(10, n, 2).value != want:
        assert time.monotonic() < deadline, f"user variable {n} never became {want}"
        time.sleep(0.02)


def test_a_second_download_runs_from_its_first_instruction(page, served):
    """Issue 29 item 10. Manual 3.6.36: 129 type 0 runs "from current address", and 132/133 leave
    the program counter where the last program stopped; so the dashboard's Download ends with 131
    ("Reset program counter and stack pointer to zero"): Run then starts the new program at its
    first instruction, as in the TMCL-IDE. The first program stops on its STOP at address 4."""
    open_program(page, "    SGP 8, 2, 1\n    SGP 8, 2, 2\n    SGP 8, 2, 3\n    SGP 8, 2, 4\n")
    download(page)
    page.click("#btn-run")
    _user_variable(served, 8, 4)
    page.evaluate("OpenTMCL.programEditor.setSource('    SGP 9, 2, 42\\n    SGP 8, 2, 5\\n    SGP 8, 2, 6\\n"
                  "    SGP 8, 2, 7\\n    SGP 8, 2, 8\\n')")
    download(page)
    page.wait_for_function("document.getElementById('prog-pc').textContent === '0'", timeout=TIMEOUT_MS)
    page.click("#btn-run")
    _user_variable(served, 8, 8)
    assert served.dashboard.module.reply(10, 9, 2).value == 42   # the first instruction ran


def test_run_from_start_beside_run(page, served):
    """"Run from start" (issue 29 item 10) sits beside Run and sends 131, then 129: after the program
    stopped on its STOP, Run would start there (3.6.36 "from current address") and do nothing more;
    Run from start runs it again from its first instruction."""
    open_program(page, "    CALC LOAD, 0\n    CALC ADD, 1\n    AGP 5, 2\n    SGP 6, 2, 1\n")
    download(page)
    assert page.inner_text("#btn-run + #btn-run-start") == "Run from start"   # the next button
    page.click("#btn-run")
    _user_variable(served, 6, 1)
    served.dashboard.module.reply(9, 6, 2, 0)        # SGP 6, 2, 0 from the host
    served.dashboard.module.reply(9, 5, 2, 0)
    page.click("#btn-run-start")
    page.wait_for_function("document.getElementById('prog-message').textContent === 'run from start'",
                           timeout=TIMEOUT_MS)
    _user_variable(served, 6, 1)
    assert served.dashboard.module.reply(10, 5, 2).value == 1       # A = 0 + 1 again: from the top
