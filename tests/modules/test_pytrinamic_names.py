"""PyTrinamic's parameter names are aliases of ours (issue 15 item 2; docs/profiles.md "Parameter aliases").

TMCM-6212 manual 3.6.5: "The specified value is written to the axis parameter specified by the
parameter number" -- a parameter is its number; a name is only a way of writing it. The tables
here are the INSTALLED PyTrinamic's own (its ``AP`` and ``GP<bank>`` classes, names and numbers),
so a PyTrinamic release that adds or renumbers a name fails this file until the profiles follow.
"""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
from pytrinamic.modules import TMCM1021, TMCM1160, TMCM1161, TMCM6212

import opentmcl
from opentmcl.host import UnknownAttributeError, UnknownParameterError
from opentmcl.modules import load_profile
from opentmcl.modules.profile_file import ProfileError

OURS = {"TMCM6212": "TMCM-6212", "TMCM1021": "PD28-1021", "TMCM1160": "PD86-1180", "TMCM1161": "PD86-1180"}
"""PyTrinamic module class -> our profile; PyTrinamic has no TMCM-1180 class, its table is the
TMCM-1160's / TMCM-1161's (the PD86-1180 manual V4.45 is the TMCM-1180's and -1160's family)."""
CLASSES = {"TMCM6212": TMCM6212, "TMCM1021": TMCM1021, "TMCM1160": TMCM1160, "TMCM1161": TMCM1161}

_NOT_6212 = "not in the TMCM-6212 manual V1.05 axis parameter table (4.1)"
_NOT_1180 = "not in the PD86-1180 / TMCM-1180 manual V4.45 parameter tables (5, 6)"
EXCLUDED = {
    ("TMCM6212", "AP", "PWMScale"): _NOT_6212,
    ("TMCM6212", "AP", "PWMMode"): _NOT_6212,
    ("TMCM6212", "AP", "PWMFrequency"): _NOT_6212,
    ("TMCM6212", "AP", "PWMAutoscale"): _NOT_6212,
    ("TMCM6212", "AP", "LatchedActualPosition"): _NOT_6212,
    ("TMCM6212", "AP", "LatchedEncoderPosition"): _NOT_6212,
    ("TMCM6212", "AP", "GroupIndex"): _NOT_6212,
    ("TMCM6212", "AP", "ReverseShaft"): _NOT_6212,
    **{(cls, "AP", name): _NOT_1180 for cls in ("TMCM1160", "TMCM1161")
       for name in ("EndSwitchPowerDown", "RandomTOffMode", "extendedErrorFlags")},
    **{("TMCM1160", "AP", name): _NOT_1180
       for name in ("externalEncoderPosition", "externalEncoderPrescaler", "ExternalEncoderMax_Deviation")},
    **{(cls, "GP0", name): _NOT_1180 for cls in ("TMCM1160", "TMCM1161")
       for name in ("reverseShaftDirection", "SuppressReply")},
    ("TMCM1160", "GP0", "lastTmclError"): _NOT_1180,
    ("TMCM1161", "GP3", "input_2"): _NOT_1180 + ": the module has interrupt inputs 0 and 1 only",
    ("TMCM1161", "GP3", "input_3"): _NOT_1180 + ": the module has interrupt inputs 0 and 1 only",
}
"""PyTrinamic names whose number our profile lacks, with the reason; the first test keeps this
list honest (no stale entry)."""


def pytrinamic_table(cls_name: str) -> list[tuple[str, str, int | None, int]]:
    """(table, name, bank, number) of every entry of the installed PyTrinamic's AP and GPn classes."""
    cls = CLASSES[cls_name]
    tables: list[tuple[str, int | None, type]] = [("AP", None, cls._MotorTypeA.AP)]
    tables += [(f"GP{b}", b, getattr(cls, f"GP{b}")) for b in range(256) if hasattr(cls, f"GP{b}")]
    return [(table, name, bank, number) for table, bank, attrs in tables
            for name, number in vars(attrs).items() if not name.startswith("_") and isinstance(number, int)]


def _has(profile, bank: int | None, number: int) -> bool:
    return number in profile.axis_parameters if bank is None else (bank, number) in profile.global_parameters


@pytest.fixture(scope="module")
def modules():
    made = {name: opentmcl.connect(f"sim://{name}") for name in set(OURS.values())}
    yield made
    for m in made.values():
        m.close()


@pytest.mark.parametrize("cls_name", sorted(OURS))
def test_every_pytrinamic_name_with_our_number_resolves_to_it(cls_name, modules):
    """Each name of PyTrinamic's table for this module, in any case, names the same number (and, for
    a global parameter, the same bank: "bank 0 is used for global parameters ... Bank 3 is used for
    interrupt configuration", TMCM-6212 manual 3.6.7) through the host API a user calls."""
    m = modules[OURS[cls_name]]
    checked = 0
    for table, name, bank, number in pytrinamic_table(cls_name):
        if not _has(m.profile, bank, number):
            assert (cls_name, table, name) in EXCLUDED, f"{cls_name}.{table}.{name} = {number}: neither ours nor excluded"
            continue
        for spelling in (name, name.upper(), name.lower(), name.swapcase()):
            if bank is None:
                assert m.axes[0].param(spelling).number == number, (cls_name, spelling)
            else:
                p = m.global_param(spelling)
                assert (p.bank, p.number) == (bank, number), (cls_name, spelling)
        checked += 1
    assert checked >= 40  # the table was read, not skipped
    # and the exclusions are current: each is in PyTrinamic's table, its number still missing here
    table = {(t, name): (bank, number) for t, name, bank, number in pytrinamic_table(cls_name)}
    for (cls, t, name), reason in EXCLUDED.items():
        if cls == cls_name:
            assert (t, name) in table, f"{cls}.{t}.{name} is no longer in PyTrinamic ({reason})"
            assert not _has(m.profile, *table[(t, name)]), f"{cls}.{t}.{name}: we have it now; drop the exclusion"


@pytest.mark.parametrize("ours", sorted(set(OURS.values())))
def test_every_alias_of_a_builtin_profile_is_a_pytrinamic_name_of_that_number(ours):
    """The aliases are facts taken from PyTrinamic (names and numbers), not names of our own."""
    theirs = {(name.lower(), bank, number) for cls, mod in OURS.items() if mod == ours
              for _, name, bank, number in pytrinamic_table(cls)}
    profile = load_profile(ours)
    params = [*profile.axis_parameters.values(), *profile.global_parameters.values()]
    aliases = [(alias, p.bank, p.number) for p in params for alias in p.aliases]
    assert len(aliases) >= 40
    for alias, bank, number in aliases:
        assert (alias.lower(), bank, number) in theirs, f"{ours}: alias {alias} of {bank}/{number} is not PyTrinamic's"


def test_pytrinamic_names_work_on_the_wire():
    """SAP/GAP/GGP by PyTrinamic name reach the numbers of the manual: AP 4 "Maximum positioning
    speed", AP 1 "Actual position" (TMCM-6212 manual 4.1), GP 66 serial address (5.1), and the
    attribute form ``axis.params.MaxVelocity``."""
    with opentmcl.connect("sim://TMCM-6212@3") as m:
        ax = m.axes[1]
        ax.set("MaxVelocity", 123456)
        assert ax.get(4) == 123456
        ax.params.maxvelocity = 2000
        assert ax.params.MaxVelocity == 2000 == ax.get("max_positioning_speed")
        ax.set("ActualPosition", -777)
        assert ax.get(1) == -777 == ax.get("actualposition") == ax.position
        assert m.get_global("SerialAddress") == 3 == m.get_global("serialaddress")
        m.set_global("timer_0", 250)                     # GP3 "timer_0": bank 3, number 0
        assert m.get_global(0, bank=3) == 250


def test_manual_meaning_wins_where_pytrinamic_names_the_number_otherwise():
    """PyTrinamic calls TMCM-6212 AP 210 "EncoderClearOnNull"; the manual (4.1) says AP 210 is the
    "Encoder resolution". The alias reaches AP 210 with the manual's range and meaning."""
    with opentmcl.connect("sim://TMCM-6212") as m:
        p = m.axes[0].param("EncoderClearOnNull")
        assert (p.number, p.name) == (210, "encoder_resolution")


def test_did_you_mean_draws_on_both_vocabularies():
    """An unknown name is refused (UnknownParameterError, UnknownAttributeError for ``params.X``)
    with close names of both vocabularies: PyTrinamic's (with the name it stands for) and ours."""
    with opentmcl.connect("sim://TMCM-6212") as m:
        for typed, hint in [("MaxVelocty", "MaxVelocity (max_positioning_speed)"),
                            ("max_positioning_sped", "max_positioning_speed"),
                            ("ActualPositon", "actual_position")]:
            with pytest.raises(UnknownParameterError) as info:
                m.axes[0].get(typed)
            assert hint in str(info.value).partition("did you mean")[2], typed
            with pytest.raises(UnknownAttributeError) as attr:
                getattr(m.axes[0].params, typed)
            assert hint in str(attr.value), typed


def test_global_did_you_mean_includes_pytrinamic_names():
    with opentmcl.connect("sim://PD86-1180") as m, pytest.raises(UnknownParameterError) as info:
        m.get_global("serialBaudRat")
    assert "serialBaudRate (rs485_baud_rate)" in str(info.value)


def test_a_profile_file_declares_its_own_aliases(tmp_path):
    """docs/profiles.md: a parameter entry's `aliases` are names of that number; an entry that gives
    them replaces the inherited list (entries merge field by field)."""
    path = tmp_path / "mine.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "MINE-1"\n'
                    '[[axis_parameter]]\nnumber = 4\naliases = ["Vmax", "Top speed"]\n')
    profile = load_profile(str(path))
    assert profile.axis_parameter("VMAX").number == 4
    assert profile.axis_parameter("top_speed").number == 4
    with pytest.raises(KeyError):
        profile.axis_parameter("MaxVelocity")          # replaced, not inherited
    assert profile.axis_parameter("ActualVelocity").number == 3   # other entries keep theirs


@pytest.mark.parametrize(("entry", "message"), [
    ('aliases = "Vmax"', "axis_parameter[number=4].aliases: expected a list of names"),
    ('aliases = ["", "x"]', "axis_parameter[number=4].aliases: expected a list of names"),
    ('aliases = ["TargetPosition"]', "name 'TargetPosition' is also a name or alias of axis_parameter[number=0]"),
    ('aliases = ["actual_speed"]', "name 'actual_speed' is also a name or alias of axis_parameter[number=3]"),
])
def test_a_bad_alias_is_one_line_naming_its_key(tmp_path, entry, message):
    """An alias that is not a name, or that another entry already answers to, is refused: a name
    must name one parameter."""
    path = tmp_path / "bad.toml"
    path.write_text(f'extends = "TMCM-6212"\n[[axis_parameter]]\nnumber = 4\n{entry}\n')
    with pytest.raises(ProfileError) as info:
        load_profile(str(path))
    assert any(message in line for line in info.value.errors), info.value.errors


def test_the_readme_from_pytrinamic_example_runs_and_prints_what_it_says(tmp_path):
    """README "From PyTrinamic": its Python block runs against sim:// and each print() line's output
    is the value its trailing comment states (so the section cannot rot)."""
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")
    section = readme.split("## From PyTrinamic", 1)[1].split("\n## ", 1)[0]
    (code,) = re.findall(r"```python\n(.*?)```", section, re.S)
    stated = [line.rsplit("#", 1)[1].strip() for line in code.splitlines() if line.strip().startswith("print(")]
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == stated
    assert len(stated) == 4 and '"MaxVelocity"' in code and "motor.AP.MaxVelocity" in section
