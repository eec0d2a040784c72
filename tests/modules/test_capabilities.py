"""Capabilities in the profile data (issue 12 item 3; docs/profiles.md "Capabilities"): a user
profile that extends a built-in one and changes one capability changes that behaviour, the
engine keyword of an axis parameter maps it onto the ramp engine, and a bad capability table is
a one-line error with its key path."""
from __future__ import annotations

import copy
from dataclasses import replace
from pathlib import Path

import pytest

from opentmcl import VirtualModule
from opentmcl.modules.profile import builtin_raw, load_profile, parse_profile
from opentmcl.modules.profile_file import ProfileError, validate
from tests.capture.helpers import cli
from tests.world.conftest import Rig


def derived(tmp_path: Path, parent: str, capabilities: str = "", rest: str = "") -> str:
    """A profile file extending `parent` with the given [module.capabilities] lines."""
    path = tmp_path / "derived.toml"
    path.write_text(f'extends = "{parent}"\n[module]\nname = "DERIVED"\n'
                    f'[module.capabilities]\n{capabilities}\n{rest}')
    return str(path)


def test_an_extending_profile_inherits_the_capabilities_and_overrides_one(tmp_path):
    """docs/profiles.md: an `extends` profile states only what differs; capabilities merge key by key."""
    base = load_profile("PD86-1180").capabilities
    prof = load_profile(derived(tmp_path, "PD86-1180", "null_channel = false"))
    assert prof.capabilities == replace(base, null_channel=False) and base.null_channel


def test_unit_mode(tmp_path):
    """TMCM-6212 manual 4.1 AP255 "Units of velocity and acceleration/deceleration settings: 0 - the
    internal units of the TMC5130 are used directly": with unit_mode = false AP255 is a plain
    parameter and AP4 keeps reading pps."""
    internal = round(51200 * 2**24 / 16_000_000)
    for module, ap4 in (("TMCM-6212", internal), (derived(tmp_path, "TMCM-6212", "unit_mode = false"), 51200)):
        vm = VirtualModule(module)
        assert vm.request(5, 255, 0, 0).status == 100
        assert vm.request(6, 4, 0).value == ap4, module


def test_velocity_unit(tmp_path):
    """PD86-1180 manual 5: velocities in TMC429 internal units; `opentmcl demo` names the unit the
    profile declares (velocity_unit = "tmc429" -> internal), not the one of the engine."""
    for module, unit in (("TMCM-6212", "velocity in pps"),
                         (derived(tmp_path, "TMCM-6212", 'velocity_unit = "tmc429"'), "velocity in internal")):
        done = cli("demo", "--module", module, "--duration", "0.2")
        assert done.returncode == 0 and unit in done.stdout, (module, done.stdout[:300], done.stderr)


def test_encoder_resolution_or_prescaler(tmp_path):
    """TMCM-6212 manual 6.2: AP210 is the encoder resolution (counts per round, default 51200), so one
    round of 51200 microsteps reads 51200; PD86-1180 manual 7.2: with a prescaler AP210 = p the
    reading is the encoder's counts times p/512 (1024 counts, the profile's encoder_counts, x 100)."""
    for module, reading in (("TMCM-6212", 51200),
                            (derived(tmp_path, "TMCM-6212", 'encoder = "prescaler"'), 1024 * 51200 // 512)):
        r = Rig(module, {"axis": {"0": {}}})
        r.cmd(4, 0, 0, 51200)
        r.vm.advance(3)
        assert r.gap(1) == 51200 and r.gap(209) == reading, module


def test_encoder_counts(tmp_path):
    """PD86-1180 manual 1: "The built-in encoder has 256 steps per rotation"; 7.2: prescaler p/512,
    so p = 512 reads the encoder's own counts: 256 per round, 1024 with encoder_counts = 1024."""
    for module, counts in (("TMCM-1180", 256), (derived(tmp_path, "PD86-1180", "encoder_counts = 1024"), 1024)):
        r = Rig(module, {"axis": {"0": {}}})
        r.sap(210, 512)
        round_ = 200 * (1 << r.gap(140))
        r.cmd(4, 0, 0, round_)
        r.vm.advance(30)
        assert r.gap(1) == round_ and r.gap(209) == counts, module


def test_null_channel(tmp_path):
    """PD86-1180 manual 7.2: adding 4 to p "Clear encoder with next null channel event"; a module
    without the null channel keeps counting (and AP210 keeps its + 4)."""
    cases = (("TMCM-1180", 5000 + 100 - 3200, 6400),
             (derived(tmp_path, "PD86-1180", "null_channel = false"), 5000, 6404))
    for module, encoder, ap210 in cases:
        r = Rig(module, {"axis": {"0": {"start": 100}}})
        r.sap(210, 6400 + 4)
        r.cmd(4, 0, 0, 5000)
        r.vm.advance(30)
        assert (r.gap(1), r.gap(209), r.gap(210)) == (5000, encoder, ap210), module


def test_reference_input(tmp_path):
    """PD86-1180 manual 7.1: "The reference switch is connected in series with the left limit
    switch": with reference_input = "REFL" an active home switch reads as the left limit switch
    (AP11); with "HOME" it has an input of its own (AP9) and the left switch stays off."""
    scenario = {"axis": {"0": {"left": {"position": -25000}, "home": {"position": 2000, "width": 400}}}}
    for module, left in (("TMCM-1180", 1), (derived(tmp_path, "PD86-1180", 'reference_input = "HOME"'), 0)):
        r = Rig(module, scenario)
        r.vm.world.axis(0).force_switch("home", 1)
        assert (r.gap(11), r.gap(9)) == (left, 1), module


def test_freewheel_delay(tmp_path):
    """PD86-1180 manual 5 AP204 "Time after which the power to the motor will be cut when its
    velocity has reached zero"; on the TMCM-6212 AP204 is the freewheeling mode (4.1), no delay."""
    for module, cut in (("TMCM-1180", True), (derived(tmp_path, "PD86-1180", "freewheel_delay = false"), False)):
        r = Rig(module, {"axis": {"0": {}}})
        r.sap(204, 100)
        r.vm.advance(0.2)
        assert r.gap(180) == (0 if cut else r.gap(6) >> 3), module


def test_an_axis_parameter_maps_onto_the_ramp_engine(tmp_path):
    """TMCM-6212 manual 4.1 AP4 "The maximum speed used for positioning ramps": which parameter sets
    the engine's maximum speed is profile data. Here AP4 drives nothing and a new AP250 does."""
    rest = ('[[axis_parameter]]\nnumber = 4\nengine = ""\n'
            '[[axis_parameter]]\nnumber = 250\nname = "my_speed"\nmin = 0\nmax = 100000\naccess = "RW"\n'
            'default = 51200\nengine = "max_positioning_speed"\n')
    path = derived(tmp_path, "TMCM-6212", rest=rest)
    assert load_profile(path).engine_params[250] == "max_positioning_speed" and 4 not in load_profile(path).engine_params
    vm = VirtualModule(path)
    assert vm.request(5, 250, 0, 1000).status == 100 and vm.request(5, 4, 0, 500).status == 100
    vm.request(4, 0, 0, 10**6)
    vm.advance(2)
    assert vm.request(6, 3, 0).value == 1000


@pytest.mark.parametrize("capabilities, rest, message", [
    ("warp_drive = true", "", "module.capabilities.warp_drive: unknown capability"),
    ('encoder = "optical"', "", "module.capabilities.encoder: must be one of resolution, prescaler, got 'optical'"),
    ('reference_input = "refl"', "", "module.capabilities.reference_input: must be one of HOME, REFL"),
    ("null_channel = 1", "", "module.capabilities.null_channel: expected true or false, got 1"),
    ('unit_mode = "yes"', "", "module.capabilities.unit_mode: expected true or false"),
    ("encoder_counts = 0", "", "module.capabilities.encoder_counts: must be positive, got 0"),
    ("encoder_counts = true", "", "module.capabilities.encoder_counts: expected an integer, got True"),
    ('usb = "no"', "", "module.capabilities.usb: expected true or false, got 'no'"),
    ("", '[[io]]\nbank = 1\nport = 8\nmeasures = "current"\n',
     "io[bank=1,port=8].measures: must be one of supply_voltage, temperature, got 'current'"),
    ("", '[[io]]\nbank = 1\nport = 8\nper_unit = 0\n', "io[bank=1,port=8].per_unit: expected counts per unit"),
    ("", '[[axis_parameter]]\nnumber = 4\nmeasures = "temperature"\n',
     "axis_parameter[number=4].measures: only an I/O port measures a quantity of the world"),
    ("", '[[axis_parameter]]\nnumber = 4\nengine = "max speed"\n',
     "axis_parameter[number=4].engine: expected a ramp engine keyword"),
    ("", '[[axis_parameter]]\nnumber = 4\nengine = 4\n', "axis_parameter[number=4].engine: expected a string"),
    ("", '[[global_parameter]]\nbank = 0\nnumber = 66\nengine = "max_positioning_speed"\n',
     "global_parameter[bank=0,number=66].engine: only an axis parameter drives the ramp engine"),
])
def test_bad_capabilities_are_one_line_errors(tmp_path, capabilities, rest, message):
    """docs/profiles.md: every error one line with its key path; `profile check` exits 1."""
    path = derived(tmp_path, "PD86-1180", capabilities, rest)
    with pytest.raises(ProfileError) as err:
        load_profile(path)
    assert any(message in line for line in err.value.errors), err.value.errors
    done = cli("profile", "check", path)
    assert done.returncode == 1 and message in done.stderr and "Traceback" not in done.stderr


def test_capability_edges(tmp_path):
    """The last valid values: encoder_counts = 1, reference_input = "HOME" (its first invalid
    values are in the test above)."""
    prof = load_profile(derived(tmp_path, "PD86-1180", 'encoder_counts = 1\nreference_input = "HOME"'))
    assert (prof.capabilities.encoder_counts, prof.capabilities.reference_input) == (1, "HOME")


def test_a_standalone_profile_declares_every_capability():
    """docs/profiles.md: a profile without `extends` must declare [module.capabilities] and each key."""
    raw = copy.deepcopy(builtin_raw("PD28-1021"))
    assert validate(raw) == []
    del raw["module"]["capabilities"]["encoder"]
    assert validate(raw) == ["module.capabilities.encoder: missing"]
    del raw["module"]["capabilities"]
    assert validate(raw) == ["module.capabilities: missing table [module.capabilities] (docs/profiles.md)"]


def test_usb_is_the_one_capability_a_profile_may_leave_out():
    """docs/profiles.md: `usb` came after the schema was published; a standalone profile without it
    keeps the former default (a pty serving it alone stands for USB, docs/endpoints.md)."""
    raw = copy.deepcopy(builtin_raw("PD28-1021"))
    assert raw["module"]["capabilities"].pop("usb") is False   # manual title page: "RS485 interface"
    assert validate(raw) == []
    assert parse_profile(raw).capabilities.usb is True


def test_capabilities_that_are_not_a_table_are_named_so(tmp_path):
    """docs/profiles.md: "Every key is required in a resolved profile" and each error is one line
    with its key path; `capabilities = 3` is there but is not the [module.capabilities] table."""
    path = tmp_path / "flat.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "FLAT"\ncapabilities = 3\n')
    done = cli("profile", "check", str(path))
    assert done.returncode == 1 and "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines() == [f"{path}: module.capabilities: expected a table, got 3"]


def test_an_io_range_with_only_min_is_checked_not_a_crash(tmp_path):
    """docs/profiles.md: io `min`/`max` are optional (0 and 1); a `min` alone above the default max
    is reported like any range (it used to raise KeyError out of `profile check`)."""
    path = tmp_path / "io.toml"
    new_port = '[[io]]\nbank = 0\nport = 99\nname = "IN99"\nkind = "digital"\naccess = "R"\n'
    path.write_text(f'extends = "PD86-1180"\n{new_port}min = 5\n')
    done = cli("profile", "check", str(path))
    assert done.returncode == 1 and "Traceback" not in done.stderr
    assert "io[bank=0,port=99]: min 5 is greater than max 1" in done.stderr
    path.write_text(f'extends = "PD86-1180"\n{new_port}min = 1\n')   # the last valid min
    assert cli("profile", "check", str(path)).returncode == 0


def test_a_probed_module_without_a_built_in_match_declares_capabilities(tmp_path):
    """docs/profiles.md `profile probe`: with no built-in of that module number the skeleton is a
    standalone profile (a linear engine); it declares the PD28-1021's capabilities and loads."""
    from opentmcl.host.probe import ProbeResult, skeleton

    path = tmp_path / "probed.toml"
    path.write_text(skeleton(ProbeResult("9999V100", None, 1, {0: {4: 1000}}), "sim://"))
    prof = load_profile(str(path))
    assert prof.engine == "linear" and prof.capabilities == load_profile("PD28-1021").capabilities


@pytest.mark.parametrize("parent", ["TMCM-6212", "PD28-1021", "PD86-1180"])
def test_an_engine_keyword_the_engine_lacks_is_a_profile_error(tmp_path, parent):
    """docs/profiles.md: the engine refuses a keyword it does not have when the module is built; the
    CLI prints one line (exit 2: bad input, docs/cli.md), no internal error."""
    path = derived(tmp_path, parent, rest='[[axis_parameter]]\nnumber = 4\nengine = "warp"\n')
    with pytest.raises(ProfileError, match="ramp engine refuses the profile's settings.*warp"):
        VirtualModule(path)
    done = cli("demo", "--module", path, "--duration", "0.1")
    assert done.returncode == 2 and "warp" in done.stderr and "internal error" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_a_probed_module_without_a_built_in_match_guesses_the_base_command_set(tmp_path):
    """docs/profiles.md `profile probe`: the standalone skeleton's `opcodes` are the commands 1-39
    of the manuals' overviews (TMCM-6212 3.4.1, PD86-1180 4.4.1: no 16-18 or 29) and the control
    commands with 138 (3.6.35, 3.6.36), not the PD86-1180's 139 or the PD28-1021's extended set."""
    from opentmcl.host.probe import ProbeResult, skeleton

    path = tmp_path / "probed.toml"
    path.write_text(skeleton(ProbeResult("9999V100", None, 1, {0: {4: 1000}}), "sim://"))
    ops = load_profile(str(path)).opcodes
    assert {1, 15, 19, 28, 30, 39, 128, 138} <= ops
    assert not {16, 17, 18, 29, 40, 64, 80, 139} & ops
