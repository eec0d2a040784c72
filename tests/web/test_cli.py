"""`opentmcl serve --web` and `opentmcl dashboard --to URL` start the dashboard (subprocesses)."""
from __future__ import annotations

import importlib
import json
import urllib.request

import pytest

from opentmcl.cli import CliError, main
from opentmcl.cli.dashboard import parse_web, sim_url_real_time

from .rawhttp import start_cli, stop_cli

importlib.import_module("uvicorn")


def _get(url: str) -> dict:
    with urllib.request.urlopen(url) as r:
        return json.load(r)


def test_serve_with_web_serves_the_dashboard_of_the_served_module():
    """TMCM-6212 manual 3.6.36: the overview's version string is the module's command-136 answer."""
    proc, url, _ = start_cli(["serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--web", "127.0.0.1:0"],
                             "dashboard http")
    try:
        ov = _get(url + "m/1/api/overview")
        assert ov["module"] == "TMCM-6212" and ov["version"] == "6212V105" and ov["virtual"]
    finally:
        out = stop_cli(proc)
    assert proc.returncode == 0, out
    assert "stopped" in out


def test_serve_with_web_serves_every_module_of_the_bus():
    """Two modules on one bus (serial addresses 1 and 2, global parameter 66, TMCM-6212 manual 5.1):
    both overviews are reachable, each with its command-136 version string (TMCM-6212 manual 3.6.36
    "6212V105"; PD86-1180 manual 4.6.39, firmware V4.45: "1180V445")."""
    proc, url, lines = start_cli(["serve", "--module", "TMCM-6212", "--address", "1", "--module", "PD86-1180",
                                  "--address", "2", "--tcp", "127.0.0.1:0", "--web", "127.0.0.1:0"], "dashboard http")
    try:
        modules = _get(url + "api/modules")
        assert [(m["address"], m["module"]) for m in modules] == [(1, "TMCM-6212"), (2, "PD86-1180")]
        versions = {m["address"]: _get(url + m["url"].lstrip("/") + "api/overview")["version"] for m in modules}
        assert versions == {1: "6212V105", 2: "1180V445"}
    finally:
        out = stop_cli(proc)
    assert proc.returncode == 0, out
    assert "2 modules" in lines[-1]
    assert f"PD86-1180 at address 2: {url}m/2/" in out


def test_dashboard_command_for_a_sim_url():
    proc, url, _ = start_cli(["dashboard", "--to", "sim://PD86-1180", "--web", "127.0.0.1:0"], "dashboard for")
    try:
        ov = _get(url + "m/1/api/overview")
        assert ov["module"] == "PD86-1180" and ov["axes"] == 1
    finally:
        stop_cli(proc)
    assert proc.returncode == 0


def test_sim_urls_run_on_the_wall_clock_unless_told():
    assert "clock=real" in sim_url_real_time("sim://TMCM-6212")
    assert sim_url_real_time("sim://TMCM-6212?clock=virtual").endswith("clock=virtual")
    assert sim_url_real_time("tcp://127.0.0.1:2323") == "tcp://127.0.0.1:2323"


def test_web_address_parsing():
    assert parse_web("127.0.0.1:8080") == ("127.0.0.1", 8080)
    assert parse_web("8080") == ("127.0.0.1", 8080)
    with pytest.raises(CliError):
        parse_web("localhost:http")


def test_dashboard_without_url_is_a_one_line_error(capsys, monkeypatch):
    monkeypatch.delenv("OPENTMCL_URL", raising=False)
    assert main(["dashboard"]) == 2
    assert "--to" in capsys.readouterr().err


def test_dashboard_with_unknown_module_is_a_one_line_error(capsys):
    assert main(["dashboard", "--to", "sim://TMCM-9999", "--web", "127.0.0.1:0"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "TMCM-9999" in err


def test_dashboard_on_a_port_in_use_is_a_one_line_error(capsys):
    """The page cannot be served where another program listens: one line naming the address."""
    import socket

    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        assert main(["dashboard", "--to", "sim://TMCM-6212", "--web", f"127.0.0.1:{port}"]) == 2
    err = capsys.readouterr().err
    assert f"127.0.0.1:{port}" in err and "in use" in err
    assert "Traceback" not in err and "ERROR" not in err


def test_dashboard_with_a_timeout_that_is_not_positive_is_refused(capsys):
    """--timeout is how long to wait for each reply: 0 or less cannot be waited for."""
    assert main(["dashboard", "--to", "sim://TMCM-6212", "--timeout", "-1", "--web", "127.0.0.1:0"]) == 2
    assert "--timeout" in capsys.readouterr().err
