"""Bad input on every `opentmcl` subcommand, in process.

House rule (DEVELOPERS.md): "Bad input gets a clear error and loses nothing: status codes on the
wire, typed exceptions in the library, non-zero exit and a one-line message in the CLI - never a
traceback, a hang or a corrupted EEPROM file." Each case expects exit status 2 and one stderr line
that names the problem; files given as input are unchanged afterwards.
"""
import json

import pytest

from opentmcl.cli import main
from opentmcl.lang.binfile import decode

SIM = "sim://TMCM-6212"


def one_line_error(capsys, argv, *words):
    """Exit 2, one stderr line starting 'opentmcl', naming each of `words`; returns that line."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("opentmcl ") and "Traceback" not in err
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


@pytest.fixture
def files(tmp_path):
    (tmp_path / "ok.tmc").write_text("MVP ABS, 0, 1000\nSTOP\n")
    (tmp_path / "garbage.bin").write_bytes(bytes(range(7, 247)) * 3)
    (tmp_path / "empty.bin").write_bytes(b"")
    (tmp_path / "adir").mkdir()
    return tmp_path


def test_usage_errors_are_one_line_and_status_2(capsys):
    """House rule: "a one-line message in the CLI" - also for argparse's own errors (bad int,
    missing required option), which used to print the whole usage block; main() returns 2 in
    process instead of raising SystemExit."""
    one_line_error(capsys, ["send", "GAP 1, 0", "--to", SIM, "--address", "abc"], "--address", "'abc'")
    one_line_error(capsys, ["serve"], "--module")
    one_line_error(capsys, ["tmc4210", "convert", "-p", "1", "--hz-per-s", "-1e300"], "--hz-per-s")


def test_asm_output_in_a_missing_folder_creates_nothing(capsys, files):
    """House rule: a typo in an output path is "a clear error", not a silently created folder; the
    check runs before anything is written, so no .bin appears for a bad listing path."""
    one_line_error(capsys, ["asm", str(files / "ok.tmc"), "-o", str(files / "nope" / "x.bin")],
                   "folder", "does not exist")
    one_line_error(capsys, ["asm", str(files / "ok.tmc"), "-l", str(files / "nope" / "x.lst")], "nope")
    assert not (files / "nope").exists() and not (files / "ok.bin").exists()


def test_asm_binary_to_stdout(capsysbinary, files, monkeypatch):
    """`-o -` writes the 8-byte records to stdout (not to a file named '-')."""
    monkeypatch.chdir(files)
    assert main(["asm", "ok.tmc", "-o", "-"]) == 0
    out = capsysbinary.readouterr().out
    assert [tuple(i) for i in decode(out)][0] == (4, 0, 0, 1000)
    assert not (files / "-").exists()


def test_asm_only_one_output_on_stdout(capsys, files):
    """Two outputs on stdout would interleave: a clear error instead."""
    one_line_error(capsys, ["asm", str(files / "ok.tmc"), "-o", "-", "-l", "-"], "stdout")


def test_asm_names_file_line_and_column(capsys, files):
    """The assembler names file:line:column of a syntax error."""
    src = files / "bad.tmc"
    src.write_text("GAP 1, 0\n  MVP FOO, 0, 1\n")
    one_line_error(capsys, ["asm", str(src)], "bad.tmc:2:7", "FOO")


def test_disasm_bad_label_tables(capsys, files):
    """A label table that is binary or names a label twice is a clear error, not exit 1 with a
    codec message or a silently dropped label."""
    assert main(["asm", str(files / "ok.tmc")]) == 0
    binary = str(files / "ok.bin")
    one_line_error(capsys, ["disasm", binary, "-s", str(files / "garbage.bin")], "garbage.bin", "UTF-8")
    twice = files / "twice.sym"
    twice.write_text("start 0\nstart 1\n")
    one_line_error(capsys, ["disasm", binary, "-s", str(twice)], "twice.sym:2", "start")
    one_line_error(capsys, ["disasm", str(files / "garbage.bin")], "checksum")


def test_load_empty_binary_and_bad_timeout(capsys, files):
    """An empty .bin is no program; --timeout NaN or 0 would wait forever or never."""
    one_line_error(capsys, ["load", str(files / "empty.bin"), "--to", SIM], "empty program")
    one_line_error(capsys, ["load", str(files / "ok.tmc"), "--to", SIM, "--timeout", "nan"], "--timeout")
    one_line_error(capsys, ["debug", str(files / "ok.tmc"), "--timeout", "0"], "--timeout")


@pytest.mark.parametrize("option", [["--seconds", "nan"], ["--seconds", "inf"], ["--sample", "nan"],
                                    ["--sample", "inf"], ["--sample", "1e-300"], ["--timeout", "nan"]])
def test_run_rejects_non_finite_times(capsys, files, option):
    """NaN/inf used to end in an internal error (OverflowError) or exit 1; a tiny --sample in a
    practically endless virtual run."""
    one_line_error(capsys, ["run", str(files / "ok.tmc"), *option], option[0])


def test_run_watch_numbers_are_bytes(capsys, files):
    """Manual 3.1: type and motor/bank are bytes, so var99999 cannot be watched (was exit 1)."""
    one_line_error(capsys, ["run", str(files / "ok.tmc"), "-w", "var99999"], "var99999", "0..255")


def _eeprom(path, **over):
    data = {"format": "opentmcl-eeprom", "version": 1, "module": "TMCM-6212", "axis": {}, "global": {},
            "user": {}, "coord": {}, "program": []}
    data.update(over)
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize("command", ["run", "debug", "serve"])
@pytest.mark.parametrize("over", [{"axis": [1, 2], "global": "x"}, {"user": {"1": 1.5}},
                                  {"axis": {"0": {"4": "fast"}}}, {"program": [[9999, 0, 0, 0]]},
                                  {"version": 99}])
def test_damaged_eeprom_files_are_refused_unchanged(capsys, files, command, over):
    """House rule: "never ... a corrupted EEPROM file": a file with wrong section types, non-integer
    values or a newer version is refused (it used to crash with AttributeError/TypeError, or be
    rewritten with Infinity and version 1), and its bytes stay as they were."""
    path = _eeprom(files / "e.json", **over)
    before = path.read_bytes()
    argv = (["serve", "-m", "TMCM-6212", "--eeprom", str(path)] if command == "serve"
            else [command, str(files / "ok.tmc"), "--eeprom", str(path)])
    one_line_error(capsys, argv, "e.json")
    assert path.read_bytes() == before


@pytest.mark.parametrize("content", [b'{"format":"opentmcl-eeprom"', b"", b"\xa4\x00garbage", b"[]"])
def test_unreadable_eeprom_files_are_refused_unchanged(capsys, files, content):
    """Corrupt JSON, an empty file and binary garbage: a one-line error, the bytes unchanged."""
    path = files / "e.json"
    path.write_bytes(content)
    one_line_error(capsys, ["run", str(files / "ok.tmc"), "--eeprom", str(path)], "e.json")
    assert path.read_bytes() == content


def test_eeprom_of_another_module_and_missing_folder(capsys, files):
    """Another module's EEPROM is refused unchanged; a new EEPROM file in a missing folder is an
    error, not a new folder."""
    other = _eeprom(files / "other.json", module="PD86-1180")
    before = other.read_bytes()
    one_line_error(capsys, ["run", str(files / "ok.tmc"), "--eeprom", str(other)], "PD86-1180")
    assert other.read_bytes() == before
    one_line_error(capsys, ["run", str(files / "ok.tmc"), "--eeprom", str(files / "nope" / "e.json")],
                   "does not exist")
    assert not (files / "nope").exists()


def test_debug_command_file_must_be_text(capsys, files):
    """`debug -x FILE` with binary garbage: one line, not exit 1 with a codec message."""
    one_line_error(capsys, ["debug", str(files / "ok.tmc"), "-x", str(files / "garbage.bin")], "UTF-8")


def test_serve_unknown_module_is_named_once(capsys):
    """The message names the unknown module and the known ones, once."""
    line = one_line_error(capsys, ["serve", "-m", "TMCM-9999"], "TMCM-9999", "TMCM-6212")
    assert line.count("TMCM-9999") == 1


def test_tmc4210_convert_huge_values(capsys):
    """Datasheet 6.1.12: velocity is -2047..2047 and A_MAX 0..2047; a value far beyond them is a
    one-line error (was an internal OverflowError) with a readable number."""
    one_line_error(capsys, ["tmc4210", "convert", "-p", "1", "-r", "1", "--hz-per-s", "1e300"], "A_MAX")
    line = one_line_error(capsys, ["tmc4210", "convert", "-p", "1", "--hz", "1e300"], "2047")
    assert len(line) < 200


@pytest.mark.parametrize("url", ["tcp://", "tcp://127.0.0.1:99999", "serial://", "can://socketcan",
                                 "sim://TMCM-9999", "http://x", "foo"])
def test_send_bad_urls(capsys, url):
    """Malformed URLs of every scheme: one line naming the problem, nothing sent."""
    one_line_error(capsys, ["send", "GAP 1, 0", "--to", url])


def test_outputs_never_overwrite_inputs(capsys, files):
    """House rule: bad input "loses nothing": `asm x.tmc -o x.tmc` used to replace the source with
    binary records and `disasm x.bin -o x.bin` the binary with text."""
    src = files / "ok.tmc"
    before = src.read_bytes()
    one_line_error(capsys, ["asm", str(src), "-o", str(src)], "overwrite the source")
    one_line_error(capsys, ["asm", str(src), "-l", str(files / "." / "ok.tmc")], "overwrite the source")
    one_line_error(capsys, ["asm", str(src), "-l", str(files / "a"), "-s", str(files / "a")], "same file")
    assert src.read_bytes() == before
    assert main(["asm", str(src)]) == 0
    binary = files / "ok.bin"
    image = binary.read_bytes()
    capsys.readouterr()
    one_line_error(capsys, ["disasm", str(binary), "-o", str(binary)], "overwrite the input")
    assert binary.read_bytes() == image


def test_trace_csv_never_overwrites_inputs(capsys, files):
    """House rule "loses nothing": `demo --scenario s.toml --csv s.toml` and `run p.tmc --csv p.tmc`
    used to replace the input with the trace."""
    scenario = files / "s.toml"
    scenario.write_text('module = "TMCM-6212"\n')
    before = scenario.read_bytes()
    one_line_error(capsys, ["demo", "--scenario", str(scenario), "--csv", str(scenario)], "overwrite the scenario")
    assert scenario.read_bytes() == before
    program = files / "ok.tmc"
    text = program.read_bytes()
    one_line_error(capsys, ["run", str(program), "--csv", str(program)], "overwrite the program")
    one_line_error(capsys, ["run", str(program), "--eeprom", str(files / "e.json"), "--csv", str(files / "e.json")],
                   "--eeprom")
    assert program.read_bytes() == text and not (files / "e.json").exists()


def test_addresses_beyond_32_bits(capsys, files):
    """Manual 3.1: the value of a request is 32 bits; --from / --start beyond that used to end with
    exit 1 and no option named."""
    one_line_error(capsys, ["run", str(files / "ok.tmc"), "--from", "99999999999999999999"], "--from")
    assert main(["asm", str(files / "ok.tmc")]) == 0
    capsys.readouterr()
    one_line_error(capsys, ["load", str(files / "ok.bin"), "--to", SIM, "--start", "99999999999999999999"],
                   "--start")


@pytest.fixture
def captures(files):
    """A valid capture (the TMCM-6212 example) and the damaged files a user may hand over."""
    from pathlib import Path

    good = Path(__file__).resolve().parents[2] / "examples" / "captures" / "tmcm6212_program_reference_events.jsonl"
    text = good.read_text()
    bad = {
        "truncated.jsonl": text[:300] + "\n" + text.splitlines()[-1] + "\n",   # torn, then a line: not the end
        "wrong_json.jsonl": '{"record": "header", "format": "opentmcl-capture",\n',
        "huge_line.jsonl": '{"record": "header", "x": "' + "a" * 100_000 + '"}\n',
        "version2.jsonl": text.replace('"version":1,', '"version":2,', 1),
        "empty.jsonl": "",
    }
    head = text.splitlines()[0]
    request = ('{"record": "frame", "n": 1, "t": %s, "dir": "host", "kind": "request", "raw": "01 06 01 00 00 00 '
               '00 00 08", "address": 1, "command": 6, "type": 1, "motor": 0, "value": 0}')
    for name, t in [("nan_time.jsonl", "NaN"), ("inf_time.jsonl", "1e400"), ("negative_time.jsonl", "-5")]:
        bad[name] = f"{head}\n{request % t}\n"
    for name, content in bad.items():
        (files / name).write_text(content)
    (files / "junk.jsonl").write_bytes(bytes(range(256)) * 8)
    return good, {**{name: files / name for name in bad}, "junk.jsonl": files / "junk.jsonl",
                  "zero": "/dev/zero", "dir": files / "adir"}


@pytest.mark.parametrize("argv", [["log", "show"], ["log", "show", "--command", "GAP"],
                                  ["replay"], ["replay", "--module", "TMCM-6212"]])
@pytest.mark.parametrize("case", ["truncated.jsonl", "wrong_json.jsonl", "huge_line.jsonl", "version2.jsonl",
                                  "empty.jsonl", "junk.jsonl", "zero", "dir",
                                  "nan_time.jsonl", "inf_time.jsonl", "negative_time.jsonl"])
def test_bad_capture_files(capsys, captures, argv, case):
    """docs/capture.md: "anything that is not a version-1 capture" is "a one-line error naming the
    file and line (exit 2)", also a line longer than MAX_LINE_BYTES and an endless /dev/zero. The
    message names the subcommand (`opentmcl log: error: ...`; old code printed `opentmcl None:`
    and, with --command GAP, `opentmcl GAP:`). A frame's `t` is "seconds since the proxy started":
    NaN, infinity or a negative time is refused (old code: shown, and replay crashed, exit 1/3).
    A line cut short is an error when another line follows it (issue 30 item 4; a torn last line is
    skipped with a warning, tests/capture/test_format.py)."""
    path = captures[1][case]
    line = one_line_error(capsys, [*argv[:2], str(path), *argv[2:]] if argv[0] == "log" else
                          [argv[0], str(path), *argv[1:]], str(path))
    assert line.startswith(f"opentmcl {argv[0]}: error: "), line


def test_log_show_and_replay_bad_options(capsys, captures):
    """Unknown mnemonics, tolerances, modules and addresses are one-line errors, exit 2."""
    good = str(captures[0])
    one_line_error(capsys, ["log", "show", good, "--command", "FOO"], "opentmcl log: error", "FOO")
    one_line_error(capsys, ["replay", good, "--tolerance", "warp=1"], "opentmcl replay: error", "warp")
    one_line_error(capsys, ["replay", good, "--tolerance", "position=-1"], "position", ">= 0")
    one_line_error(capsys, ["replay", good, "--tolerance", "time=nan"], "time")
    one_line_error(capsys, ["replay", good, "--module", "TMCM-9999"], "TMCM-9999")
    one_line_error(capsys, ["replay", good, "--address", "256"], "0..255")
    one_line_error(capsys, ["replay", good, "--scenario", "/dev/zero"], "/dev/zero")


def test_profile_bad_files(capsys, files):
    """docs/profiles.md: a profile file is read up to 1 MiB; a missing, binary or endless file is one
    line naming it, exit 2 for `profile show` and for every command that takes a module file."""
    (files / "bin.toml").write_bytes(bytes(range(256)))
    for path in [files / "missing.toml", files / "bin.toml", files / "adir" / "x.toml"]:
        one_line_error(capsys, ["profile", "show", str(path)], "opentmcl profile: error", path.name)
        one_line_error(capsys, ["serve", "--module", str(path), "--pty"], path.name)
        one_line_error(capsys, ["replay", str(files / "x.jsonl"), "--module", str(path)])


def test_profile_probe_and_proxy_bad_options(capsys):
    """Bad URLs, time-outs and listener options of `profile probe` and `proxy`: one line, exit 2."""
    one_line_error(capsys, ["profile", "probe", "nope://x"], "opentmcl profile: error")
    one_line_error(capsys, ["profile", "probe", SIM, "--timeout", "nan"], "--timeout")
    one_line_error(capsys, ["profile", "probe", SIM, "--max-seconds", "-1"], "--max-seconds")
    one_line_error(capsys, ["profile", "probe", SIM, "--address", "256"], "--address")
    one_line_error(capsys, ["proxy", "--to", SIM], "opentmcl proxy: error", "--pty")
    one_line_error(capsys, ["proxy", "--to", SIM, "--tcp", "0", "--gap", "nan"], "--gap")
    one_line_error(capsys, ["proxy", "--to", SIM, "--tcp", "0", "--max-clients", "0"], "--max-clients")
    one_line_error(capsys, ["proxy", "--to", SIM, "--tcp", "0", "--idle-timeout", "inf"], "--idle-timeout")
