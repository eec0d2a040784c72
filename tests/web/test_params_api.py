"""The parameters view's endpoints (web/params.py, docs/dashboard-parameters.md) through the
guarded app (Starlette test client, virtual TMCM-6212 in virtual time). Every value is checked
through the wire with GAP/GGP (TMCM-6212 manual 3.6.6, 3.6.8)."""
from __future__ import annotations

import json

import pytest

FOREIGN = {"Origin": "http://evil.example"}



def gap(client, number: int, axis: int) -> int:
    return client.module.reply(6, number, axis).value


def exported(client, fmt: str = "json") -> str:
    r = client.get(f"/m/1/api/params/export?format={fmt}")
    assert r.status_code == 200, r.text
    return r.text


def modified(text: str, axis: int, number: int, value: int) -> str:
    data = json.loads(text)
    hit = [e for e in data["axis"] if e["axis"] == axis and e["number"] == number]
    assert len(hit) == 1
    hit[0]["value"] = value
    return json.dumps(data)


def test_values_are_one_batched_read_of_axis_and_globals(client):
    """Manual 3.6.5 SAP / 3.6.6 GAP: a value written on the wire shows in the next batched read, for
    the axis asked; globals are keyed "bank:number" (manual 5.1, bank 0 parameter 77)."""
    client.module.request(5, 4, 2, 12345)
    r = client.get("/m/1/api/params/values/2").json()
    assert r["axis"] == 2 and r["values"]["axis"]["4"] == 12345
    assert client.get("/m/1/api/params/values/0").json()["values"]["axis"]["4"] != 12345
    assert r["values"]["global"]["0:77"] == client.module.reply(10, 77, 0).value
    assert "0:66" in r["values"]["global"]   # readable, though not in a parameter set


def test_values_axis_edges(client):
    """Manual 1: six axes. Axis 5 is read; axis 6 and a non-number are 400 with a message."""
    assert client.get("/m/1/api/params/values/5").status_code == 200
    r = client.get("/m/1/api/params/values/6")
    assert r.status_code == 400 and "axes 0..5" in r.json()["error"]
    assert client.get("/m/1/api/params/values/x").status_code == 400


@pytest.mark.parametrize("fmt", ["json", "toml"])
def test_export_is_a_file_with_module_firmware_numbers_and_names(client, fmt):
    """Manual 3.6.36: the firmware version "6212V105" and module name travel with the values."""
    r = client.get(f"/m/1/api/params/export?format={fmt}")
    assert r.status_code == 200
    assert r.headers["content-disposition"] == f'attachment; filename="TMCM-6212-address1.{fmt}"'
    assert "6212V105" in r.text and "max_positioning_speed" in r.text and "TMCM-6212" in r.text
    assert client.get("/m/1/api/params/export?format=xml").status_code == 400


@pytest.mark.parametrize("fmt", ["json", "toml"])
def test_diff_shows_the_change_and_apply_writes_it(client, fmt):
    """Import of a modified file: the diff names number, name, current and file value and writes
    nothing; apply writes it (GAP 4 of axis 1 confirms, manual 3.6.6)."""
    before = gap(client, 4, 1)
    text = exported(client, fmt)
    if fmt == "json":
        text = modified(text, 1, 4, 20000)
    else:
        marker = f'[[axis]]\naxis = 1\nnumber = 4\nname = "max_positioning_speed"\nvalue = {before}\n'
        assert marker in text
        text = text.replace(marker, marker.replace(f"value = {before}", "value = 20000"))
    r = client.post("/m/1/api/params/diff", json={"text": text})
    assert r.status_code == 200, r.text
    assert r.json()["changes"] == [{"kind": "axis", "index": 1, "number": 4, "name": "max_positioning_speed",
                                    "current": before, "value": 20000}]
    assert gap(client, 4, 1) == before  # the diff applies nothing
    r = client.post("/m/1/api/params/apply", json={"text": text})
    assert r.status_code == 200 and r.json()["applied"] == 1
    assert gap(client, 4, 1) == 20000


def test_foreign_module_file_is_refused_and_nothing_applied(client):
    """A PD86-1180 file is refused with a message naming both modules."""
    data = json.loads(modified(exported(client), 0, 4, 1000))
    data["module"] = "PD86-1180"
    for route in ("diff", "apply"):
        r = client.post(f"/m/1/api/params/{route}", json={"text": json.dumps(data)})
        assert r.status_code == 400
        assert "PD86-1180" in r.json()["error"] and "TMCM-6212" in r.json()["error"]
    assert gap(client, 4, 0) != 1000


def test_out_of_range_value_is_refused_and_nothing_applied(client):
    """Manual 4.1 axis parameter 4: 0...7999774. A file with 7999775 and a valid change of axis
    parameter 7 (0...255) applies neither; the last valid value 7999774 applies."""
    before7 = gap(client, 7, 0)
    text = modified(modified(exported(client), 0, 4, 7999775), 0, 7, (before7 + 8) % 256)
    r = client.post("/m/1/api/params/apply", json={"text": text})
    assert r.status_code == 400 and "7999775" in r.json()["error"] and r.json()["problems"]
    assert gap(client, 7, 0) == before7 and gap(client, 4, 0) != 7999775
    r = client.post("/m/1/api/params/apply", json={"text": modified(exported(client), 0, 4, 7999774)})
    assert r.status_code == 200 and gap(client, 4, 0) == 7999774


@pytest.mark.parametrize("body", [{"text": 5}, {}, {"text": "not a file"}, {"text": "{"}])
def test_bad_import_bodies_are_400(client, body):
    r = client.post("/m/1/api/params/diff", json=body)
    assert r.status_code == 400 and "\n" not in r.json()["error"]


def test_import_must_be_json(client):
    r = client.post("/m/1/api/params/apply", content=b'{"text": ""}', headers={"Content-Type": "text/plain"})
    assert r.status_code == 400


@pytest.mark.parametrize("route", ["/m/1/api/params/diff", "/m/1/api/params/apply", "/m/1/api/charts/subscribe"])
def test_a_foreign_origin_is_refused(client, route):
    """docs/dashboard.md "Threat model": a POST with another site's Origin is 403 before the route
    runs, so the module keeps its values."""
    text = modified(exported(client), 0, 4, 1000)
    body = {"text": text, "series": [{"kind": "axis", "index": 0, "number": 206}]}
    r = client.post(route, json=body, headers=FOREIGN)
    assert r.status_code == 403 and "Origin" in r.json()["error"]
    assert gap(client, 4, 0) != 1000
