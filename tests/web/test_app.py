"""The dashboard's HTTP API and WebSocket (Starlette test client, virtual module in virtual time)."""
from __future__ import annotations

import pytest


def test_page_and_static_files_are_served_without_cdn(client):
    """The module's page is at /m/ADDRESS/ (GP 66 "Serial address", default 1, TMCM-6212 manual 5.1);
    the root leads there."""
    assert client.get("/", follow_redirects=False).headers["location"] == "/m/1/"
    page = client.get("/")
    assert page.status_code == 200 and "OpenTMCL" in page.text and str(page.url).endswith("/m/1/")
    assert "http://" not in page.text and "https://" not in page.text  # works offline
    for name in ("app.js", "params.js", "charts.js", "editor.js", "style.css"):
        r = client.get(f"/static/{name}")
        assert r.status_code == 200
        assert "https://" not in r.text


def test_console_endpoint(client):
    """TMCM-6212 manual 3.6.4 MVP ABS; the reply carries status 100 and its text."""
    r = client.post("/m/1/api/console", json={"line": "MVP ABS, 1, 1000"})
    assert r.status_code == 200 and r.json()["status"] == 100
    assert client.dash.module.axes[1].target_position == 1000


def test_bad_requests_are_400_with_a_message(client):
    assert client.post("/m/1/api/console", content=b"not json").status_code == 400
    r = client.post("/m/1/api/params/axis", json={"axis": 0, "number": 4, "value": "fast"})
    assert r.status_code == 400 and "integer" in r.json()["error"]
    r = client.post("/m/1/api/params/axis", json={"axis": 0, "number": 4, "value": 8000000})
    assert r.status_code == 400 and "Invalid value" in r.json()["error"]  # manual 3.2 status 4
    assert client.post("/m/1/api/program/breakpoints", json={"lines": "3"}).status_code == 400
    assert client.get("/m/1/api/params/axis/x").status_code == 400


def test_parameter_endpoints(client):
    """Manual 3.6.5 SAP: a value written is read back (GAP)."""
    r = client.post("/m/1/api/params/axis", json={"axis": 0, "number": 5, "value": "0x1000"})
    assert r.json() == {"value": 4096}
    table = client.get("/m/1/api/params/axis/0").json()["params"]
    assert next(p for p in table if p["number"] == 5)["value"] == 4096
    glob = client.get("/m/1/api/params/global").json()["params"]
    assert any(p["number"] == 66 and p["bank"] == 0 for p in glob)


def test_program_endpoints(client):
    """Manual 3.6.36: download (132/133), step (130), status (135)."""
    r = client.post("/m/1/api/program/assemble", json={"source": "  JA Nowhere\n"})
    assert r.json()["ok"] is False and r.json()["errors"][0]["line"] == 1
    r = client.post("/m/1/api/program/download", json={"source": "  CALC LOAD, 9\n  STOP\n"})
    assert r.json()["ok"] and "_program" not in r.json()
    st = client.post("/m/1/api/program/step", json={}).json()
    assert st["pc"] == 1 and st["a"] == 9
    assert client.get("/m/1/api/program").json()["state"]["line"] == 2


def test_websocket_streams_samples_and_state(client):
    client.dash.sample_fast()
    client.dash.sample_slow()
    with client.websocket_connect("ws://127.0.0.1/m/1/ws", subprotocols=["opentmcl"]) as ws:
        hello = ws.receive_json()
        assert hello["type"] == "hello" and hello["overview"]["module"] == "TMCM-6212"
        kinds = {ws.receive_json()["type"] for _ in range(2)}
        assert kinds == {"samples", "state"}


def test_posts_must_be_json_so_other_sites_cannot_forge_them(client):
    """A cross-site form or text/plain fetch cannot carry application/json without a preflight."""
    r = client.post("/m/1/api/console", content=b'{"line": "MVP ABS, 0, 1000"}',
                    headers={"Content-Type": "text/plain"})
    assert r.status_code == 400
    assert client.dash.module.axes[0].target_position == 0


def test_websocket_refuses_other_origins(client):
    from starlette.testclient import WebSocketDenialResponse
    from starlette.websockets import WebSocketDisconnect

    with pytest.raises((WebSocketDisconnect, WebSocketDenialResponse)), \
            client.websocket_connect("ws://127.0.0.1/m/1/ws", headers={"Origin": "http://evil.example"},
                                     subprotocols=["opentmcl"]) as ws:
        ws.receive_json()


def test_operands_outside_the_frame_are_400_not_500(client):
    """TMCM-6212 manual 3.1: a command carries an 8-bit instruction number, type and motor/bank and a
    4-byte value. Operands that do not fit are refused with a message (no server error) and nothing
    is sent."""
    cases = [
        ("/m/1/api/params/axis", {"axis": 0, "number": 4, "value": 2**40}, "32 bits"),
        ("/m/1/api/params/store", {"kind": "global", "number": 4, "index": 2**40, "restore": False}, "0..255"),
        ("/m/1/api/io/output", {"bank": 2, "port": 0, "value": 2**40}, "32 bits"),
        ("/m/1/api/console", {"line": "300, 0, 0, 0"}, "0..255"),
    ]
    for path, body, words in cases:
        r = client.post(path, json=body)
        assert r.status_code == 400, (path, r.text)
        assert words in r.json()["error"]
