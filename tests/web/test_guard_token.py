"""A dashboard for the LAN (`--allow-host NAME`, or a non-loopback bind) also needs the token printed at
start-up (docs/dashboard.md "Exposing it on a LAN"), against real processes and sockets."""
from __future__ import annotations

import importlib
import re
import urllib.parse

import pytest

from opentmcl.cli import main

from .rawhttp import get_json, page_headers, post_json, request, start_cli, stop_cli, target, ws_upgrade

importlib.import_module("uvicorn")

NAME = "mybox.example"


@pytest.fixture(scope="module")
def lan():
    """`opentmcl dashboard --allow-host mybox.example` (bound to loopback: the test stays local)."""
    proc, url, lines = start_cli(["dashboard", "--to", "sim://TMCM-6212", "--web", "127.0.0.1:0",
                                  "--allow-host", NAME], "dashboard for")
    try:
        more = [next(proc.stdout) for _ in range(2)]
        parts = urllib.parse.urlsplit(url)
        token = urllib.parse.parse_qs(parts.query)["token"][0]
        yield parts.port, token, "".join(lines + more)
    finally:
        stop_cli(proc)


def test_the_token_is_printed_with_every_url_to_open(lan):
    port, token, out = lan
    assert len(token) >= 32 and re.fullmatch(r"[A-Za-z0-9_-]+", token)
    assert f"http://127.0.0.1:{port}/?token={token}" in out
    assert f"also at http://{NAME}:{port}/?token={token}" in out


def test_the_allowed_name_without_the_token_is_refused(lan):
    port, token, _ = lan
    for host in (f"{NAME}:{port}", f"127.0.0.1:{port}"):
        r = request(port, "GET", "/m/1/api/params/global", host=host)
        assert r.status == 403 and "token" in r.error
        assert request(port, "GET", "/m/1/api/overview", host=host,
                       headers={"X-OpenTMCL-Token": token[:-1] + ("A" if token[-1] != "A" else "B")}).status == 403
    ok = get_json(port, "/m/1/api/overview", host=f"{NAME}:{port}", headers={"X-OpenTMCL-Token": token})
    assert ok["version"] == "6212V105"  # TMCM-6212 manual 3.6.36 command 136
    assert request(port, "GET", "/m/1/api/overview", host=f"other.example:{port}",
                   headers={"X-OpenTMCL-Token": token}).status == 403  # still only the names allowed


def test_opening_the_printed_url_sets_a_strict_cookie_and_drops_the_token(lan):
    port, token, _ = lan
    r = request(port, "GET", f"/?token={token}", host=f"{NAME}:{port}")
    assert r.status == 303 and r.headers["location"] == "/"
    cookie = r.headers["set-cookie"]
    name_value = cookie.split(";")[0]
    assert name_value == f"opentmcl_token_{port}={token}"
    attrs = {a.strip().lower() for a in cookie.split(";")[1:]}
    assert {"httponly", "samesite=strict", "path=/"} <= attrs
    with_cookie = {"Cookie": name_value}
    assert request(port, "GET", "/m/1/", host=f"{NAME}:{port}", headers=with_cookie).status == 200
    origin = f"http://{NAME}:{port}"
    assert ws_upgrade(port, "/m/1/ws", host=f"{NAME}:{port}", origin=origin, extra=with_cookie).status == 101
    assert ws_upgrade(port, "/m/1/ws", host=f"{NAME}:{port}", origin=origin).status == 403


def test_the_cookie_alone_does_not_make_a_request_state_changing(lan):
    """Manual 3.6.4 MVP ABS from the console: with the cookie but without X-OpenTMCL (a form) it is
    refused; with the page's headers it moves the target."""
    port, token, _ = lan
    host = f"{NAME}:{port}"
    auth = {"Cookie": f"opentmcl_token_{port}={token}"}
    r = request(port, "POST", "/m/1/api/console", host=host, body=b"line=MVP+ABS%2C+0%2C+99",
                headers={**auth, "Content-Type": "application/x-www-form-urlencoded"})
    assert r.status == 403 and "X-OpenTMCL" in r.error
    assert target(port, host=host, headers=auth) != 99
    headers = {**page_headers(port), "Origin": f"http://{host}", **auth}
    r = post_json(port, "/m/1/api/console", {"line": "MVP ABS, 0, 99"}, host=host, headers=headers)
    assert r.status == 200 and r.json()["status"] == 100
    assert target(port, host=host, headers=auth) == 99


def test_a_non_loopback_bind_implies_a_token():
    """Binding the wildcard address (every interface) requires the token even without --allow-host."""
    import opentmcl
    from opentmcl.web import start_dashboard

    module = opentmcl.connect("sim://TMCM-6212")
    with start_dashboard(module, "0.0.0.0", 0, on_stop=module.close, poll=False) as handle:
        assert handle.token and handle.open_url.endswith(f"?token={handle.token}")
        assert request(handle.port, "GET", "/m/1/api/overview").status == 403
        assert request(handle.port, "GET", "/m/1/api/overview",
                       headers={"X-OpenTMCL-Token": handle.token}).status == 200
    module = opentmcl.connect("sim://TMCM-6212")
    with start_dashboard(module, "127.0.0.1", 0, on_stop=module.close, poll=False) as handle:
        assert handle.token is None and handle.open_url == handle.url  # loopback: no token


@pytest.mark.parametrize("argv, words", [
    (["dashboard", "--to", "sim://TMCM-6212", "--web", "127.0.0.1:0", "--allow-host", "http://mybox"], "without scheme"),
    (["dashboard", "--to", "sim://TMCM-6212", "--web", "127.0.0.1:0", "--allow-host", "mybox:8080"], "or port"),
    (["dashboard", "--to", "sim://TMCM-6212", "--web", "127.0.0.1:0", "--allow-host", ""], "host name"),
    (["serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--allow-host", "mybox"], "--web"),
])
def test_bad_allow_host_is_a_one_line_usage_error(capsys, argv, words):
    """One line naming the option and what is wrong, exit code 2 (a usage error, as every CLI one)."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--allow-host" in err and words in err and "unrecognized" not in err
    assert "Traceback" not in err and err.count("\n") == 1


def test_allow_host_accepts_names_and_addresses():
    """The edge: names, IPv4, IPv6 with or without brackets are taken as they are."""
    from opentmcl.web.server import check_allowed_hosts

    assert check_allowed_hosts(["MyBox.lan", "192.168.1.20", "fe80::1", "[fd00::2]"]) == \
        ("mybox.lan", "192.168.1.20", "fe80::1", "fd00::2")


def test_serve_web_with_allow_host_requires_the_printed_token():
    """`opentmcl serve --web ... --allow-host NAME` prints the dashboard URL with its token; the
    overview (TMCM-6212 manual 3.6.36 command 136, "6212V105") needs it."""
    proc, url, _ = start_cli(["serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0", "--web", "127.0.0.1:0",
                              "--allow-host", NAME], "dashboard http")
    try:
        also = next(proc.stdout)
        parts = urllib.parse.urlsplit(url)
        token = urllib.parse.parse_qs(parts.query)["token"][0]
        host = f"{NAME}:{parts.port}"
        assert request(parts.port, "GET", "/m/1/api/overview", host=host).status == 403
        ov = get_json(parts.port, "/m/1/api/overview", host=host, headers={"X-OpenTMCL-Token": token})
        assert ov["version"] == "6212V105"
    finally:
        stop_cli(proc)
    assert proc.returncode == 0 and also.strip() == f"also at http://{NAME}:{parts.port}/?token={token}"


@pytest.mark.parametrize("path", ["//evil.example/", "///evil.example/x", "/\\evil.example/", "/\\/evil.example/"])
def test_opening_a_token_url_never_redirects_off_site(lan, path):
    """Issue 28 item 5: "`GET //evil.example/?token=T` redirects off-site". The redirect that drops
    the token names a path of this site: one leading slash (a browser reads `//host` and `/\\host`
    as another site), so the Location never leaves the dashboard."""
    port, token, _ = lan
    r = request(port, "GET", f"{path}?token={token}", host=f"{NAME}:{port}")
    assert r.status == 303, (r.status, r.body[:200])
    location = r.headers["location"]
    assert location.startswith("/") and location[1:2] not in ("/", "\\"), location
    assert "evil.example" in location  # the path kept, as a path of this site
    assert urllib.parse.urlsplit(urllib.parse.urljoin(f"http://{NAME}:{port}/", location)).netloc == f"{NAME}:{port}"
