"""The assemble endpoint behind the program view returns every error and warning with file, line,
column and severity (docs/dashboard-program.md), and the vendored editor ships with its licence."""
from __future__ import annotations

from importlib import resources

from starlette.testclient import TestClient

import opentmcl
from opentmcl.web.app import create_app
from opentmcl.web.service import Dashboard


def test_every_error_and_warning_with_its_position(client):
    """Issue 15 item 6: all errors at once, and the module's capability warnings - "ROR 7, 1000"
    on the six-axis TMCM-6212 (manual 1 "Features")."""
    source = "    ROR 7, 1000\n    FOO 1\n    SAP 4, 0, Speed\n    JA Nowhere\n"
    out = client.post("/m/1/api/program/assemble", json={"source": source}).json()
    assert out["ok"] is False and out["more"] == 0
    assert [(d["line"], d["column"], d["severity"]) for d in out["diagnostics"]] == [
        (1, 9, "warning"), (2, 5, "error"), (3, 15, "error"), (4, 8, "error")]
    assert [d["message"] for d in out["errors"]] == ["unknown mnemonic 'FOO'", "undefined symbol 'Speed'",
                                                     "undefined symbol 'Nowhere'"]
    assert [d["file"] for d in out["diagnostics"]] == ["<editor>"] * 4
    assert out["warnings"] == [{"file": "<editor>", "line": 1, "column": 9, "severity": "warning",
                                "message": "ROR: motor 7 does not exist on TMCM-6212 (motors 0..5)"}]


def test_a_clean_program_with_warnings_still_downloads(client):
    """Warnings do not stop the download (132 ... 133, manual 3.6.36): the program is stored."""
    out = client.post("/m/1/api/program/download", json={"source": "SAP 250, 0, 1\nSTOP\n"}).json()
    assert out["ok"] is True and out["count"] == 3
    assert [(d["line"], d["severity"], d["message"]) for d in out["warnings"]] == [
        (1, "warning", "SAP: TMCM-6212 has no axis parameter 250")]
    assert client.dash.program is not None


def test_more_than_fifty_errors_are_counted(client):
    out = client.post("/m/1/api/program/assemble",
                      json={"source": "".join(f"BAD{i}\n" for i in range(53))}).json()
    assert len(out["errors"]) == 50 and out["more"] == 3


def test_the_vendored_editor_is_served_with_its_licence(client):
    """CodeMirror 5 is a static asset of the package (no CDN): script, stylesheet, licence and
    README with name and version beside them."""
    for name in ("codemirror.js", "codemirror.css"):
        r = client.get(f"/static/vendor/codemirror/{name}")
        assert r.status_code == 200 and len(r.content) > 1000
    assert client.get("/static/editor.css").status_code == 200
    folder = resources.files("opentmcl.web").joinpath("static", "vendor", "codemirror")
    assert "MIT License" in folder.joinpath("LICENSE").read_text()
    readme = folder.joinpath("README.md").read_text()
    assert "5.65.21" in readme and "MIT" in readme
    assert 'CodeMirror.version = "5.65.21"' in client.get("/static/vendor/codemirror/codemirror.js").text
    page = client.get("/m/1/").text
    assert page.index("vendor/codemirror/codemirror.js") < page.index("static/app.js")


def test_a_module_with_its_own_profile_file_is_checked_by_that_profile(tmp_path):
    """Issue 15 item 6: "the dashboard editor ... warn[s] or refuse[s] instructions the module cannot
    execute"; docs/profiles.md: a module described by a profile file is checked by that file. The
    editor of a two-axis variant assembles (it used to fail on the profile's name, which no built-in
    module has) and names motor 2 as the first missing one."""
    path = tmp_path / "two.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "TMCM-2212"\naxes = 2\n')
    module = opentmcl.connect(f"sim://{path}", profile=str(path))
    transport = module.client.transport
    dash = Dashboard(module, vm=transport.module, vm_lock=transport.lock)
    try:
        with TestClient(create_app(dash), base_url="http://127.0.0.1", headers={"X-OpenTMCL": "1"}) as c:
            out = c.post("/m/1/api/program/assemble", json={"source": "ROR 1, 10\nROR 2, 10\n"}).json()
    finally:
        module.close()
    assert out["ok"] is True and out["count"] == 3
    assert [(d["line"], d["column"], d["message"]) for d in out["warnings"]] == [
        (2, 5, "ROR: motor 2 does not exist on TMCM-2212 (motors 0..1)")]
