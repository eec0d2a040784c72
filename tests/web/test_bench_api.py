"""The tuning bench's server side (issue 31) without a browser: virtual modules in virtual time behind
the Starlette test client, checked with GAP/GGP on the module's own client. Units (TMCM-6212
manual 6.5, PD86-1180 manual 5), the wizards' all-or-none apply and EEPROM store, the world load of
a virtual module only, program read-back with 134 (3.6.36), the profile keys the page reads."""
from __future__ import annotations

import importlib
import json
import tomllib

import pytest

importlib.import_module("starlette")
from starlette.testclient import TestClient  # noqa: E402

import opentmcl  # noqa: E402
from opentmcl.modules import load_profile  # noqa: E402
from opentmcl.modules.profile_file import ProfileError  # noqa: E402
from opentmcl.web.app import create_app  # noqa: E402
from opentmcl.web.service import Dashboard  # noqa: E402
from opentmcl.web.setup import reference_modes  # noqa: E402

GAP, SAP, SGP, GGP = 6, 5, 9, 10


def serve(url: str, virtual: bool = True):
    module = opentmcl.connect(url)
    t = module.client.transport
    d = Dashboard(module, vm=t.module if virtual else None, vm_lock=t.lock)
    return TestClient(create_app(d), base_url="http://127.0.0.1", headers={"X-OpenTMCL": "1"}), d


@pytest.fixture
def six():
    c, d = serve("sim://TMCM-6212")
    with c:
        yield c, d
    d.module.client.close()


@pytest.fixture
def pd86():
    c, d = serve("sim://PD86-1180")
    with c:
        yield c, d
    d.module.client.close()


def gap(d: Dashboard, number: int, axis: int = 0) -> int:
    return d.module.client.reply(GAP, number, axis).value


# --- units ---------------------------------------------------------------------------------

def test_units_factors_of_the_tmcm_6212(six):
    """Manual 6.5: "with a 200 fullsteps motor and a microstep setting of 256 (axis parameter #140 =
    8), a velocity of 51200pps will result in 1rps (60rpm)": AP140 = 8 gives 256 microsteps and
    AP202 = 200 full steps (51200 per round), pps at 1 pps per unit (AP255 = 1); AP255 = 0 is the
    TMC5130's unit, 16 MHz / 2^24 pps per unit. The current scale is manual 1's 1.1 A RMS / 1.5 A
    peak in 32 steps."""
    c, d = six
    r = c.get("/m/1/api/units").json()
    a0 = r["axes"][0]
    assert (a0["microsteps"] * a0["fullsteps"], a0["pps_per_unit"], a0["velocity_unit"]) == (51200, 1.0, "pps")
    assert (r["current"]["rms_ma"], r["current"]["peak_ma"], r["current"]["steps"]) == (1100, 1500, 32)
    assert r["analog_volts"] is None  # no manual gives the analog inputs a voltage scale
    d.module.client.request(SAP, 255, 3, 0)
    d.module.client.request(SAP, 140, 3, 4)
    a3 = c.get("/m/1/api/units").json()["axes"][3]
    assert a3["velocity_unit"] == "internal" and a3["pps_per_unit"] == 16_000_000 / 2**24
    assert a3["pps2_per_unit"] == 16_000_000**2 / 2**41 and a3["microsteps"] == 16


def test_units_factors_of_the_pd86_1180(pd86):
    """PD86-1180 manual 5 (TMC429): v [µsteps/s] = 16 MHz * v / (65536 * 2^pulse_divisor) with the
    default pulse divisor AP154 = 3, a = 16 MHz^2 * a / (2^29 * 2^(pulse + ramp divisor)) with AP153
    = 7; no AP202 (200 full steps assumed, said so); currents by the manual's formula
    I_RMS = value * 6.6 A / 255 (steps 0: linear)."""
    c, _ = pd86
    r = c.get("/m/1/api/units").json()
    a0 = r["axes"][0]
    assert a0["pps_per_unit"] == pytest.approx(16e6 / (65536 * 8))
    assert a0["pps2_per_unit"] == pytest.approx(16e6**2 / (2**29 * 2**10))
    assert a0["fullsteps"] == 200 and "no AP202" in a0["fullsteps_from"]
    assert (r["current"]["rms_ma"], r["current"]["peak_ma"], r["current"]["steps"]) == (6600, 9300, 0)


def test_unit_settings_are_checked_and_kept_with_the_export(six):
    """Issue 31: a unit "given once per axis and kept with the parameter export". A user scale
    needs a name and positive lead and gear; the JSON and TOML exports carry the settings, and a
    diff/apply of such a file hands them back (and keeps them on the dashboard)."""
    c, d = six
    assert c.post("/m/1/api/units", json={"axis": 0, "setting": {"kind": "furlong"}}).status_code == 400
    bad = {"kind": "user", "name": "mm", "per_round": 0, "gear": 1}
    assert "per_round" in c.post("/m/1/api/units", json={"axis": 0, "setting": bad}).json()["error"]
    assert c.post("/m/1/api/units", json={"axis": 6, "setting": {"kind": "rpm"}}).status_code == 400
    mm = {"kind": "user", "name": "mm", "per_round": 5, "gear": 2}
    assert c.post("/m/1/api/units", json={"axis": 0, "setting": mm}).json()["setting"] == {**mm, "per_round": 5.0, "gear": 2.0}
    c.post("/m/1/api/units", json={"axis": 5, "setting": {"kind": "rpm"}})
    as_json = c.get("/m/1/api/params/export?format=json").text
    assert json.loads(as_json)["units"] == [{"axis": 0, "kind": "user", "name": "mm", "per_round": 5.0, "gear": 2.0},
                                            {"axis": 5, "kind": "rpm"}]
    as_toml = c.get("/m/1/api/params/export?format=toml").text
    assert tomllib.loads(as_toml)["units"][1] == {"axis": 5, "kind": "rpm"}
    d.units.clear()
    assert c.post("/m/1/api/params/diff", json={"text": as_toml}).json()["units"]["5"] == {"kind": "rpm"}
    assert c.post("/m/1/api/params/apply", json={"text": as_json}).json()["units"]["0"]["name"] == "mm"
    assert d.units[5] == {"kind": "rpm"}


# --- wizards: read and apply ---------------------------------------------------------------

def test_apply_writes_all_or_none(pd86):
    """PD86-1180 manual GP73 locks the configuration EEPROM: an auto-stored global parameter (GP77)
    is then refused with status 5 "Configuration EEPROM locked" (4.2). A wizard's SAP 4 before it
    is written back to its old value, and the error names what was undone."""
    c, d = pd86
    before = gap(d, 4)
    d.module.client.request(SGP, 73, 0, 1234)
    writes = [{"kind": "axis", "index": 0, "number": 4, "value": 123},
              {"kind": "global", "index": 0, "number": 77, "value": 1}]
    r = c.post("/m/1/api/setup/apply", json={"writes": writes})
    assert r.status_code == 400 and "nothing kept (1 value(s) written back)" in r.json()["error"]
    assert gap(d, 4) == before


def test_apply_checks_every_value_before_the_first_write(six):
    """Manual 4.1: AP7 takes 0...255. 256 (the first invalid value) after a valid AP6 is refused
    before anything is sent; 255 (the last valid one) is written, with the values it replaced."""
    c, d = six
    r = c.post("/m/1/api/setup/apply", json={"writes": [{"kind": "axis", "index": 1, "number": 6, "value": 127},
                                                        {"kind": "axis", "index": 1, "number": 7, "value": 256}]})
    assert r.status_code == 400 and "nothing written" in r.json()["error"] and gap(d, 6, 1) == 128
    r = c.post("/m/1/api/setup/apply", json={"writes": [{"kind": "axis", "index": 1, "number": 7, "value": 255}]}).json()
    assert r["sent"] == ["SAP 7, 1, 255"] and r["old"] == [{"kind": "axis", "index": 1, "number": 7, "value": 8}]
    assert gap(d, 7, 1) == 255
    r = c.post("/m/1/api/setup/apply", json={"writes": [{"kind": "axis", "index": 1, "number": 3, "value": 0}]})
    assert r.status_code == 400 and "cannot be written" in r.json()["error"]  # AP3 is read-only


def test_store_uses_stap_where_the_module_has_it(six, pd86):
    """TMCM-6212 manual 3.4.1 lists no STAP: its axis values are reported as not stored. The
    PD86-1180 has STAP (4.6.7): a stored AP4 comes back with RSAP after another SAP."""
    c, _ = six
    r = c.post("/m/1/api/setup/apply", json={"writes": [{"kind": "axis", "index": 0, "number": 4, "value": 1000}],
                                             "store": True}).json()
    assert r["stored"] == [] and r["not_stored"] == ["axis parameter 4: TMCM-6212 has no STAP"]
    c86, d86 = pd86
    r = c86.post("/m/1/api/setup/apply", json={"writes": [{"kind": "axis", "index": 0, "number": 4, "value": 777}],
                                               "store": True}).json()
    assert r["stored"] == ["STAP 4, 0"]
    d86.module.client.request(SAP, 4, 0, 5)
    d86.module.client.request(8, 4, 0, 0)  # RSAP
    assert gap(d86, 4) == 777


def test_a_store_refused_takes_the_values_back(pd86):
    """EEPROM locked (GP73 = 1234): STAP is refused with status 5, so the SAP before it is undone."""
    c, d = pd86
    before = gap(d, 4)
    d.module.client.request(SGP, 73, 0, 1234)
    r = c.post("/m/1/api/setup/apply", json={"writes": [{"kind": "axis", "index": 0, "number": 4, "value": 99}], "store": True})
    assert r.status_code == 400 and "STAP" in r.json()["error"] and gap(d, 4) == before


def test_apply_refuses_a_wizard_of_another_module_page(six):
    c, d = six
    r = c.post("/m/1/api/setup/apply", json={"writes": [{"kind": "axis", "index": 0, "number": 6, "value": 1}], "module": 2})
    assert r.status_code == 400 and gap(d, 6) == 128


def test_read_names_values(six):
    """GAP, GGP and GIO in one request, in order (manual 3.6.6, 3.6.8, 3.6.13)."""
    c, _ = six
    r = c.post("/m/1/api/setup/read", json={"values": [{"kind": "axis", "index": 2, "number": 6},
                                                       {"kind": "global", "index": 0, "number": 75},
                                                       {"kind": "io", "index": 1, "number": 0}]}).json()
    assert [v["value"] for v in r["values"]] == [128, 0, 0]
    assert c.post("/m/1/api/setup/read", json={"values": []}).status_code == 400
    assert c.post("/m/1/api/setup/read", json={"values": [{"kind": "axis", "index": 0, "number": 99}]}).status_code == 400


def test_reference_modes_in_the_manuals_words():
    """TMCM-6212 manual 6.1 Table 21, and 6.1.5: "set axis parameter #193 to 129" inverts the home
    switch of mode 5 (129..132 are modes 5..8 inverted); +64 searches the right switch (6.1.1)."""
    modes = {m["mode"]: m["text"] for m in reference_modes(load_profile("TMCM-6212"))}
    assert modes[1] == "search left stop switch only"
    assert modes[65].startswith("search left stop switch only; the right switch instead")
    assert modes[129].startswith("search home switch in negative direction, reverse the direction")
    assert modes[136].startswith("search home switch in negative direction, ignore end switches")
    three = {m["mode"]: m["text"] for m in reference_modes(load_profile("PD86-1180"))}
    assert sorted(three) == [1, 2, 3, 129, 130, 131] and "three-switch" in three[3]


# --- the world load of a virtual module ------------------------------------------------------

def test_load_only_on_a_virtual_module(six):
    """docs/world.md: the load value AP206 falls linearly with the load. A load of 0.4 of the
    full-current torque on turning axis 4 lowers AP206; null gives the scenario's load (0) back."""
    c, d = six
    d.module.client.request(1, 0, 4, 51200)  # ROR 4, 51200
    d.module.client.transport.module.advance(1.0)
    free = gap(d, 206, 4)
    assert c.post("/m/1/api/world/load", json={"axis": 4, "load": 0.4}).json() == {"axis": 4, "virtual": True, "load": 0.4}
    assert gap(d, 206, 4) < free
    assert c.post("/m/1/api/world/load", json={"axis": 4, "load": None}).json()["load"] == 0
    assert gap(d, 206, 4) == free
    assert c.post("/m/1/api/world/load", json={"axis": 4, "load": -0.1}).status_code == 400
    assert c.post("/m/1/api/world/load", json={"axis": 4, "load": 10.5}).status_code == 400


def test_load_is_refused_for_a_module_on_a_link():
    """A module the dashboard reaches over a link (here without its in-process module) has no world
    the dashboard may touch: 400, and the virtual module behind it keeps its load."""
    c, d = serve("sim://TMCM-6212", virtual=False)
    with c:
        assert c.get("/m/1/api/world/load/0").json() == {"axis": 0, "virtual": False, "load": None}
        r = c.post("/m/1/api/world/load", json={"axis": 0, "load": 1.0})
        assert r.status_code == 400 and "only to a virtual module" in r.json()["error"]
        assert d.module.client.transport.module.world.axis(0).load_now() == 0
    d.module.client.close()


# --- program read-back ---------------------------------------------------------------------

SOURCE = "    SAP 4, 0, 51200\nLoop:\n    MVP ABS, 0, 1000\n    WAIT POS, 0, 0\n    JA Loop\n"


def test_read_back_disassembles_with_labels_and_compares(six):
    """Manual 3.6.36, 134 "read program memory": the program downloaded comes back, disassembled
    with the editor's label names when it is the same program; a changed editor line is a
    difference at its address (1, line 3), with a unified diff of the two disassemblies."""
    c, d = six
    assert d.download(SOURCE)["ok"]
    r = c.post("/m/1/api/program/readback", json={"source": SOURCE}).json()
    assert r["same"] and r["count"] == 5 and r["differences"] == [] and "Loop:" in r["source"]
    again = d.assemble(r["source"])["_program"]
    assert [tuple(i) for i in again.instructions] == [(5, 4, 0, 51200), (4, 0, 0, 1000), (27, 1, 0, 0), (22, 0, 0, 1), (28, 0, 0, 0)]
    r = c.post("/m/1/api/program/readback", json={"source": SOURCE.replace("1000", "2000")}).json()
    assert not r["same"] and r["differences"] == [{"address": 1, "line": 3, "editor": "MVP ABS, 0, 2000",
                                                   "module": "MVP ABS, 0, 1000"}]
    assert "-    MVP ABS, Motor0, 2000" in r["diff"] and "+    MVP ABS, Motor0, 1000" in r["diff"]


def test_read_back_of_a_protected_program_is_refused(six):
    """Code protection GP81 = 1 forbids reading the program back (134 answers status 4)."""
    c, d = six
    d.download(SOURCE)
    d.module.client.request(SGP, 81, 0, 1)
    r = c.post("/m/1/api/program/readback", json={"source": ""})
    assert r.status_code == 400 and "GP81" in r.json()["error"]


# --- the bus overview ------------------------------------------------------------------------

def test_bus_lists_every_module_with_its_axes():
    """GET /api/bus: the modules served, each with its last polled axis state and program mode."""
    a, b = serve("sim://TMCM-6212")[1], serve("sim://PD86-1180?address=2")[1]
    for d in (a, b):
        d.sample_slow()
    with TestClient(create_app([a, b]), base_url="http://127.0.0.1") as c:
        mods = c.get("/api/bus").json()["modules"]
    assert [(m["address"], m["module"], len(m["axes"]), m["program"]) for m in mods] == \
        [(1, "TMCM-6212", 6, "stop"), (2, "PD86-1180", 1, "stop")]
    for d in (a, b):
        d.module.client.close()


# --- the profile keys of the dashboard ---------------------------------------------------------

@pytest.mark.parametrize("line, message", [
    ("current_scale = { rms_ma = 0 }", "module.current_scale"),
    ("current_scale = { rms_ma = 1000, steps = 16 }", "module.current_scale"),
    ("reference_modes = []", "module.reference_modes"),
    ("reference_modes = [1, 2]", "module.reference_modes"),
    ("analog_full_scale_volts = 0", "module.analog_full_scale_volts"),
])
def test_dashboard_profile_keys_are_checked(tmp_path, line, message):
    """docs/profiles.md "For the dashboard": a bad value is a one-line ProfileError naming its key."""
    path = tmp_path / "p.toml"
    path.write_text(f'extends = "TMCM-6212"\n[module]\nname = "MY-6212"\n{line}\n')
    with pytest.raises(ProfileError, match=message):
        load_profile(str(path))


def test_a_derived_profile_gives_a_voltage_scale(tmp_path):
    """A user profile may add the analog inputs' full-scale voltage that no manual gives."""
    path = tmp_path / "p.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "MY-6212"\nanalog_full_scale_volts = 10.0\n')
    prof = load_profile(str(path))
    assert prof.extra["analog_full_scale_volts"] == 10.0 and prof.extra["current_scale"]["rms_ma"] == 1100
