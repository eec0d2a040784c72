"""Bounds of profile files (issue 28 item 5: "a profile file with `program_memory = 1e9` (or a
huge axis count or table) passes `profile check` and makes `serve` grow to 21.7 GB, then die with
"internal error: MemoryError""; "deeply nested TOML in a profile ... gives an untyped
RecursionError").

docs/profiles.md "Bounds": each bound is far above the modules of the manuals - TMCM-6212
manual 1: "program memory (non volatile) for up to 6144 TMCL commands", 6 axes; PD86-1180 and
PD28-1021: 2048 commands, 1 axis - and at or below what a 9-byte frame addresses (motor, type
and bank are bytes). A value beyond its bound is a ProfileLimitError (a ProfileError) in the
library and one line with exit status 2 in the CLI, `profile check` included; the last value
within loads.
"""
from __future__ import annotations

import resource
import subprocess
import sys
from pathlib import Path

import pytest

from opentmcl import VirtualModule
from opentmcl.modules import bounds
from opentmcl.modules.profile import BUILTIN, builtin_raw, load_profile
from opentmcl.modules.profile_file import ProfileError, ProfileLimitError, check_bounds

BASE = 'extends = "TMCM-6212"\n[module]\nname = "BIG"\n'


def write(tmp_path, text: str, name: str = "p.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _limit_memory():
    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))


def cli(*args, cwd=None) -> subprocess.CompletedProcess:
    """A real `opentmcl` process with a 3 GiB address-space limit: a regression fails fast with
    MemoryError instead of growing to 21.7 GB."""
    return subprocess.run([sys.executable, "-m", "opentmcl", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=120, stdin=subprocess.DEVNULL, preexec_fn=_limit_memory)


def refused(done: subprocess.CompletedProcess, *words: str) -> str:
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2, done.stderr[-500:]
    assert len(lines) == 1 and "Traceback" not in done.stderr and "internal error" not in done.stderr, done.stderr
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


def test_built_in_profiles_are_within_every_bound():
    """The bounds are above the three modules of the manuals: no built-in profile reaches one."""
    for name in BUILTIN:
        raw = builtin_raw(name)
        check_bounds(raw, name)
        assert not bounds.too_deep(raw)
        prof = load_profile(name)
        assert prof.program_memory <= bounds.PROGRAM_MEMORY_MAX // 10   # 6144 of 65536


@pytest.mark.parametrize(("key", "last"), [
    ("program_memory", bounds.PROGRAM_MEMORY_MAX), ("axes", bounds.AXES_MAX),
    ("coordinates", bounds.COORDINATES_MAX), ("user_variables", bounds.USER_VARIABLES_MAX),
])
def test_module_sizes_last_valid_and_first_refused(tmp_path, key, last):
    """The last value within a bound builds a module (SCO/GCO, GGP bank 2 and the program memory
    reach it); one more is a ProfileLimitError naming the key and the bound."""
    ok = write(tmp_path, BASE + f"{key} = {last}\n", "ok.toml")
    vm = VirtualModule(str(ok))
    assert getattr(vm.profile, key) == last
    if key == "program_memory":
        assert vm.program.size == last
    if key == "axes":
        assert vm.request(6, 1, last - 1).status == 100 and vm.request(6, 1, last).status != 100
    vm.close()
    bad = write(tmp_path, BASE + f"{key} = {last + 1}\n", "bad.toml")
    with pytest.raises(ProfileLimitError, match=rf"bad.toml: module.{key}: {last + 1} .*more than the {last} "):
        load_profile(str(bad))


def test_program_memory_of_a_billion_is_refused_by_every_command(tmp_path):
    """The issue's file: `profile check` (it said "ok"), `serve --module` (it grew to 21.7 GB),
    a sim:///path.toml URL, `run --module`, `replay --module` and `dashboard --to sim:///...`:
    one line naming module.program_memory and the bound, exit 2."""
    big = write(tmp_path, BASE + "program_memory = 1000000000\n", "big.toml")
    words = ("module.program_memory: 1000000000", "65536")
    refused(cli("profile", "check", big), *words)
    refused(cli("profile", "show", big), *words)
    refused(cli("serve", "--module", big, "--tcp", "127.0.0.1:0"), *words)
    refused(cli("send", "--to", f"sim://{big}", "GAP 1, 0"), *words)
    (tmp_path / "ok.tmc").write_text("STOP\n")
    refused(cli("run", tmp_path / "ok.tmc", "--module", big, "-t", "0.1"), *words)
    refused(cli("dashboard", "--to", f"sim://{big}", "--web", "127.0.0.1:0"), *words)
    capture = Path(__file__).resolve().parents[2] / "examples" / "captures" / "tmcm6212_program_reference_events.jsonl"
    refused(cli("replay", capture, "--module", big), *words)


@pytest.mark.parametrize(("table", "entry", "base"), [
    ("global_parameter", 'bank = {b}\nnumber = {n}\nname = "g{b}_{n}"\nmin = 0\nmax = 1\naccess = "RW"\n',
     len(load_profile("TMCM-6212").global_parameters)),
    ("io", 'bank = {b}\nport = {n}\nname = "p{b}_{n}"\nkind = "digital"\naccess = "R"\n',
     len(load_profile("TMCM-6212").io)),
], ids=["global_parameter", "io"])
def test_table_entries_last_valid_and_first_refused(tmp_path, table, entry, base):
    """At most ENTRIES_MAX entries per table after `extends` (TMCM-6212: 40 global parameters,
    12 ports; the bound 1024 each): the inherited ones count."""
    bound = bounds.ENTRIES_MAX[table]

    def profile(count: int) -> str:
        keys = [(b, n) for b in range(10, 20) for n in range(256)][:count]
        return BASE + "".join(f"[[{table}]]\n" + entry.format(b=b, n=n) for b, n in keys)

    ok = write(tmp_path, profile(bound - base), "ok.toml")
    assert len(getattr(load_profile(str(ok)), "global_parameters" if table != "io" else "io")) == bound
    bad = write(tmp_path, profile(bound - base + 1), "bad.toml")
    with pytest.raises(ProfileLimitError, match=rf"{table}: {bound + 1} entries, more than the {bound}"):
        load_profile(str(bad))


def test_a_standalone_table_is_bounded_before_its_duplicates_are_counted(tmp_path):
    """257 axis parameters (numbers 0..255 allow 256): refused for size, not listed one by one."""
    text = load_profile_text()
    text += "".join(f'[[axis_parameter]]\nnumber = {n % 256}\nname = "a{n}"\nmin = 0\nmax = 1\naccess = "R"\n'
                    for n in range(257))
    path = write(tmp_path, text)
    with pytest.raises(ProfileLimitError, match="axis_parameter: 257 entries, more than the 256"):
        load_profile(str(path))
    refused(cli("profile", "check", path), "axis_parameter: 257 entries")


def load_profile_text() -> str:
    """A standalone [module] table (no parameter tables)."""
    return ('[module]\nname = "SOLO"\naxes = 1\nengine = "linear"\nfirmware_version = "0000V100"\n'
            'firmware_binary = 0\nprogram_memory = 2048\nopcodes = [1, 2, 3]\n[module.capabilities]\n'
            'velocity_unit = "pps"\nunit_mode = false\nencoder = "prescaler"\nencoder_counts = 1024\n'
            'null_channel = false\nreference_input = "HOME"\nfreewheel_delay = false\n')


@pytest.mark.parametrize(("field", "bound", "make"), [
    ("name", bounds.NAME_MAX, lambda n: f'name = "{"n" * n}"'),
    ("title", bounds.NAME_MAX, lambda n: f'title = "{"t" * n}"'),
    ("description", bounds.DESCRIPTION_MAX, lambda n: f'description = "{"d" * n}"'),
    ("aliases", bounds.ALIASES_MAX, lambda n: "aliases = [" + ", ".join(f'"x{i}"' for i in range(n)) + "]"),
    ("values", bounds.LIST_MAX, lambda n: "values = [" + ", ".join(str(i % 2) for i in range(n)) + "]"),
], ids=["name", "title", "description", "aliases", "values"])
def test_strings_and_lists_of_an_entry(tmp_path, field, bound, make):
    """Names stay short enough for a capture line (docs/capture.md: 4096 bytes), lists bounded:
    the last length within loads, one more is refused naming the entry by its key."""
    ok = write(tmp_path, BASE + f"[[axis_parameter]]\nnumber = 4\n{make(bound)}\n", "ok.toml")
    load_profile(str(ok))
    bad = write(tmp_path, BASE + f"[[axis_parameter]]\nnumber = 4\n{make(bound + 1)}\n", "bad.toml")
    with pytest.raises(ProfileLimitError, match=rf"axis_parameter\[number=4\]\.{field}: {bound + 1} "):
        load_profile(str(bad))


def nested(depth: int) -> str:
    """An extra [module] key whose value is `depth` - 2 arrays deep (the file and [module] are the
    first two levels)."""
    inner = depth - 2
    return BASE + "deep = " + "[" * inner + "]" * inner + "\n"


def test_nesting_last_valid_first_refused_and_far_beyond(tmp_path):
    """NESTING_MAX levels load; one more, and 4000 levels (where the TOML parser itself runs out
    of stack, an untyped RecursionError before), are the same one-line ProfileLimitError."""
    load_profile(str(write(tmp_path, nested(bounds.NESTING_MAX), "ok.toml")))
    for depth in (bounds.NESTING_MAX + 1, 4000):
        path = write(tmp_path, nested(depth), f"deep{depth}.toml")
        with pytest.raises(ProfileLimitError, match=f"nested more than {bounds.NESTING_MAX} levels"):
            load_profile(str(path))
    refused(cli("profile", "check", tmp_path / "deep4000.toml"), "deep4000.toml", "nested")
    refused(cli("serve", "--module", tmp_path / "deep4000.toml", "--tcp", "127.0.0.1:0"), "nested")


def test_a_parent_file_beyond_a_bound_is_refused_through_extends(tmp_path):
    """A bound holds along the `extends` chain: the child names the file that asked."""
    write(tmp_path, BASE + "coordinates = 100000\n", "parent.toml")
    child = write(tmp_path, 'extends = "parent.toml"\n[module]\nname = "CHILD"\n', "child.toml")
    with pytest.raises(ProfileLimitError, match="module.coordinates: 100000"):
        load_profile(str(child))


@pytest.mark.parametrize(("text", "message"), [
    ("program_memory = 0", "module.program_memory: must be at least 1, got 0"),
    ("coordinates = -1", "module.coordinates: must be at least 0, got -1"),
    ("user_variables = 10", "module.storable_user_variables: 56 is more than the 10 user variables"),
    ("firmware_binary = 4294967296", "module.firmware_binary: must be a 32-bit value 0..4294967295"),
    ("sio_all_max = \"all\"", "module.sio_all_max: expected an integer"),
    ("pullups = 3", "module.pullups: expected a table"),
    ("[[axis_parameter]]\nnumber = 4\nmax = 4294967296", "axis_parameter[number=4].max: must be a 32-bit value"),
    ("[[axis_parameter]]\nnumber = 4\nvalues = [\"fast\"]", "axis_parameter[number=4].values: expected a list of integers"),
    ("[[axis_parameter]]\nnumber = 4\nexcluded = [-2147483649]", "axis_parameter[number=4].excluded: -2147483649 is not"),
])
def test_values_the_firmware_cannot_use_are_schema_errors(tmp_path, text, message):
    """Values a module would fail on later (IndexError for more storable than user variables, a
    reply value beyond 32 bits) are schema errors: every one listed, exit 1 from `profile check`."""
    path = write(tmp_path, BASE + text + "\n")
    with pytest.raises(ProfileError) as err:
        load_profile(str(path))
    assert not isinstance(err.value, ProfileLimitError)
    assert any(message in line for line in err.value.errors), err.value.errors
    done = cli("profile", "check", path)
    assert done.returncode == 1 and message in done.stderr and "Traceback" not in done.stderr


def test_integers_of_more_than_4300_digits_are_typed_errors(tmp_path):
    """Python's int() refuses 4300+ digits with a plain ValueError, which the TOML and YAML
    parsers let through: in a profile it is "not TOML", in a scenario a ScenarioError."""
    from opentmcl.motion.scenario import ScenarioError, load_scenario

    path = write(tmp_path, BASE + "program_memory = " + "9" * 5000 + "\n")
    with pytest.raises(ProfileError, match="not TOML"):
        load_profile(str(path))
    for name, text in (("s.toml", "x = " + "9" * 5000 + "\n"), ("s.yaml", "x: " + "9" * 5000 + "\n")):
        with pytest.raises(ScenarioError, match="4300 digits"):
            load_scenario(write(tmp_path, text, name))
