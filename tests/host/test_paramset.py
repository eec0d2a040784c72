"""Parameter sets (opentmcl.host.paramset, docs/dashboard-parameters.md) against a virtual module
over a real loopback TCP socket: export, file round trips, diff and apply with every edge refused
before anything is written."""
from __future__ import annotations

import json

import pytest

import opentmcl
from opentmcl.host import paramset as P
from opentmcl.host.errors import TmclValueError


@pytest.fixture
def module(tcp_url):
    m = opentmcl.connect(tcp_url)
    try:
        yield m
    finally:
        m.close()


def _with(ps: P.ParamSet, kind: str, index: int, number: int, value: int) -> P.ParamSet:
    """`ps` with one value replaced (the entry must exist)."""
    out, hit = [], False
    for e in ps.entries:
        if (e.kind, e.index, e.number) == (kind, index, number):
            e, hit = P.Entry(e.kind, e.index, e.number, e.name, value), True
        out.append(e)
    assert hit
    return P.ParamSet(ps.module, ps.firmware, tuple(out))


def test_export_reads_the_module_with_names_numbers_module_and_firmware(module):
    """TMCM-6212 manual 3.6.36: command 136 answers "6212V105"; manual 4.1 axis parameter 4
    "Maximum positioning speed" (written here with SAP, 3.6.5) is exported with its number and name
    for the axis it was set on; a global parameter carries its bank (manual 5.1 bank 0, 77 "auto
    start mode")."""
    module.axes[2].set(4, 12345)
    ps = P.export_set(module)
    assert (ps.module, ps.firmware) == ("TMCM-6212", "6212V105")
    by_key = {(e.kind, e.index, e.number): e for e in ps.entries}
    assert by_key[("axis", 2, 4)] == P.Entry("axis", 2, 4, "max_positioning_speed", 12345)
    assert by_key[("axis", 0, 4)].value != 12345
    assert by_key[("global", 0, 77)].name == "auto_start_mode"
    assert {e.index for e in ps.entries if e.kind == "axis"} == set(range(6))  # manual 1: six axes


def test_export_leaves_out_motion_state_and_link_settings(module):
    """Axis parameters 0/1/2 (target position, actual position, target speed; manual 4.1) would
    move the motor when imported, and global parameter 66 (serial address, manual 5.1) would cut
    the link: a set holds neither, nor read-only ones such as 3 "Actual speed" (access R)."""
    numbers = {(e.kind, e.number) for e in P.export_set(module).entries}
    for absent in [("axis", 0), ("axis", 1), ("axis", 2), ("axis", 3), ("axis", 206), ("global", 66),
                   ("global", 65), ("global", 255)]:
        assert absent not in numbers
    assert ("axis", 140) in numbers and ("axis", 174) in numbers


@pytest.mark.parametrize("dump", [P.to_json, P.to_toml])
def test_files_round_trip(module, dump):
    """JSON and TOML files read back to the same set (numbers AND names, module, firmware, axis/bank)."""
    ps = P.export_set(module)
    text = dump(ps)
    assert P.parse(text) == ps
    assert "max_positioning_speed" in text and "6212V105" in text


def test_toml_file_is_plain_toml():
    """The TOML writer's output is read by a TOML parser as tables of the documented keys."""
    import tomllib

    ps = P.ParamSet("TMCM-6212", "6212V105", (P.Entry("axis", 1, 4, "max_positioning_speed", 7999774),
                                              P.Entry("global", 3, 0, "timer_0_period", 4294967295)))
    data = tomllib.loads(P.to_toml(ps))
    assert data["axis"] == [{"axis": 1, "number": 4, "name": "max_positioning_speed", "value": 7999774}]
    assert data["global"] == [{"bank": 3, "number": 0, "name": "timer_0_period", "value": 4294967295}]


def test_diff_lists_only_changed_values_and_apply_writes_them(module):
    """Manual 3.6.5/3.6.6: after apply, GAP 4 of axis 1 answers the file's value; the diff names
    number, name, current and file value."""
    ps = P.export_set(module)
    current = module.axes[1].get(4)
    changed = _with(ps, "axis", 1, 4, 20000)
    changes = P.diff(module, P.parse(P.to_json(changed)))
    assert changes == [P.Change("axis", 1, 4, "max_positioning_speed", current, 20000)]
    assert P.apply(module, changes) == 1
    assert module.reply(6, 4, 1).value == 20000
    assert P.diff(module, changed) == []


def test_last_valid_value_applies(module):
    """Manual 4.1: axis parameter 4 takes 0...7999774 [pps]; 7999774 is accepted and written."""
    P.apply(module, [P.Entry("axis", 0, 4, "max_positioning_speed", 7999774)])
    assert module.reply(6, 4, 0).value == 7999774


def test_first_invalid_value_is_refused_and_nothing_applied(module):
    """Manual 4.1: 7999775 is one past the range of axis parameter 4. A file with one good change
    (axis parameter 7 "Standby current", 0...255) and that bad one applies neither."""
    before4, before7 = module.reply(6, 4, 0).value, module.reply(6, 7, 0).value
    ps = _with(_with(P.export_set(module), "axis", 0, 7, before7 + 1), "axis", 0, 4, 7999775)
    with pytest.raises(P.ParamSetError, match="7999775") as info:
        P.diff(module, ps)
    assert isinstance(info.value, TmclValueError)
    with pytest.raises(P.ParamSetError):
        P.apply(module, [e for e in ps.entries if e.number in (4, 7) and e.index == 0])
    assert (module.reply(6, 4, 0).value, module.reply(6, 7, 0).value) == (before4, before7)


def test_signed_range_edges(module):
    """Manual 4.1 axis parameter 174 "stallGuard2 threshold": -64...+63. -64 applies; -65 is refused."""
    P.apply(module, [P.Entry("axis", 0, 174, "stallguard2_threshold", -64)])
    assert module.reply(6, 174, 0).value == -64
    with pytest.raises(P.ParamSetError, match="-65"):
        P.apply(module, [P.Entry("axis", 0, 174, "", -65)])


def test_enumeration_refuses_a_value_between_allowed_ones(module):
    """Manual 5.1 global parameter 65 is not in a set; 77 "auto start mode" takes 0/1: 2 is refused."""
    with pytest.raises(P.ParamSetError, match="0, 1"):
        P.apply(module, [P.Entry("global", 0, 77, "auto_start_mode", 2)])


def test_foreign_module_file_is_refused(module):
    """A PD86-1180 file (its manual's own parameter table) is not applied to a TMCM-6212."""
    ps = P.ParamSet("PD86-1180", "1180V1.30", (P.Entry("axis", 0, 4, "max_positioning_speed", 1000),))
    with pytest.raises(P.ParamSetError, match="PD86-1180"):
        P.diff(module, ps)
    assert module.reply(6, 4, 0).value != 1000


def test_last_axis_and_first_missing_axis(module):
    """Manual 1: the TMCM-6212 has six axes, 0..5. Axis 5 applies; axis 6 is refused."""
    P.apply(module, [P.Entry("axis", 5, 4, "", 3000)])
    assert module.reply(6, 4, 5).value == 3000
    with pytest.raises(P.ParamSetError, match="axes 0..5"):
        P.apply(module, [P.Entry("axis", 6, 4, "", 3000)])


@pytest.mark.parametrize("entry, reason", [
    (P.Entry("axis", 0, 3, "actual_speed", 0), "not part of a parameter set"),   # access R
    (P.Entry("axis", 0, 1, "actual_position", 0), "not part of a parameter set"),
    (P.Entry("global", 0, 66, "serial_address", 2), "not part of a parameter set"),
    (P.Entry("axis", 0, 99, "", 0), "does not exist"),
    (P.Entry("axis", 0, 4, "max_acceleration", 100), "the file names it"),
    (P.Entry("global", 1, 77, "", 0), "does not exist"),
])
def test_entries_that_cannot_be_applied(module, entry, reason):
    """Read-only parameters, state, link settings, numbers the profile lacks and a name that does not
    match the number are refused; the module keeps its values."""
    before = module.reply(6, 4, 0).value
    with pytest.raises(P.ParamSetError, match=reason):
        P.apply(module, [entry, P.Entry("axis", 0, 4, "", before + 1)])
    assert module.reply(6, 4, 0).value == before


def test_duplicate_entries_are_refused():
    ps = P.ParamSet("TMCM-6212", "", (P.Entry("axis", 0, 4, "", 1), P.Entry("axis", 0, 4, "", 2)))
    with pytest.raises(P.ParamSetError, match="twice"):
        P.check(opentmcl.modules.load_profile("TMCM-6212"), ps)


@pytest.mark.parametrize("text, reason", [
    ("{", "not a JSON"),
    ("a = = 1", "not a TOML"),
    ('{"format": "other"}', "not an OpenTMCL parameter set"),
    ('{"format": "opentmcl-parameters", "version": 2, "module": "TMCM-6212"}', "version 2"),
    ('{"format": "opentmcl-parameters", "version": 1, "module": 5}', "must be strings"),
    ('{"format": "opentmcl-parameters", "version": 1, "module": "TMCM-6212", "axis": 3}', "list"),
    ('{"format": "opentmcl-parameters", "version": 1, "module": "TMCM-6212", '
     '"axis": [{"axis": 0, "number": 4, "value": true}]}', "value must be an integer"),
    ('{"format": "opentmcl-parameters", "version": 1, "module": "TMCM-6212", '
     '"axis": [{"axis": 0, "number": 4, "value": "5"}]}', "value must be an integer"),
    ("[" * 100000, "not a"),
])
def test_bad_files_raise_one_typed_error(text, reason):
    with pytest.raises(P.ParamSetError, match=reason):
        P.parse(text)


def test_file_size_is_bounded():
    """A file beyond MAX_TEXT characters is refused before it is parsed."""
    body = json.dumps({"format": P.FORMAT, "version": 1, "module": "TMCM-6212", "firmware": ""})
    P.parse(body + " " * (P.MAX_TEXT - len(body)))
    with pytest.raises(P.ParamSetError, match="larger than"):
        P.parse(body + " " * (P.MAX_TEXT - len(body) + 1))
