"""Registries for endpoints, profiles and engines, as transports have (issue 33: "Registries for
endpoints, profiles and engines, as transports already have, including entry points for
third-party ones"; docs/architecture.md "Extension points"). Each test adds an entry the way an
installed distribution does (an entry point of the group) and uses it through the public path."""
from __future__ import annotations

import subprocess
import sys
import textwrap
from importlib import metadata
from pathlib import Path

import pytest

from opentmcl import VirtualModule, registry
from opentmcl.firmware.engines import engine_names, make_engine
from opentmcl.modules.profile import load_profile, module_names, refresh
from opentmcl.server.endpoints import ENDPOINTS, EndpointOptions, make

ROOT = Path(__file__).resolve().parents[1]


def test_the_built_in_entries_are_registered():
    assert {"sixpoint", "linear", "tmc429"} <= set(engine_names())
    assert {"tcp", "pty", "can"} <= set(ENDPOINTS.available())
    assert {"TMCM-6212", "PD86-1180", "PD28-1021"} <= set(module_names())


def test_unknown_names_are_a_clear_error():
    with pytest.raises(ValueError, match="unknown motion engine 'warp'.*sixpoint"):
        make_engine("warp")
    with pytest.raises(ValueError, match="unknown endpoint 'fieldbus'.*tcp"):
        make("fieldbus", None)  # type: ignore[arg-type]
    with pytest.raises(KeyError, match="unknown module 'TMCM-9999'"):
        load_profile("TMCM-9999")


def fake_entry_points(monkeypatch, group: str, name: str, value: str) -> None:
    """An installed distribution offering `name` in `group` (what pip writes to entry_points.txt)."""
    real = metadata.entry_points

    def entry_points(**kw):
        found = list(real(**kw))
        if kw.get("group") == group:
            found.append(metadata.EntryPoint(name, value, group))
        return found
    monkeypatch.setattr(metadata, "entry_points", entry_points)


def test_a_third_party_profile_from_an_entry_point_serves_as_a_module(monkeypatch, tmp_path):
    """A profile file a distribution names, extending a built-in one (docs/profiles.md), is known
    by its name everywhere a built-in name is."""
    path = tmp_path / "rig.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "RIG-6212"\nfirmware_version = "6212V999"\n')
    module = tmp_path / "rigprofile.py"
    module.write_text(f"from pathlib import Path\nPATH = Path({str(path)!r})\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    fake_entry_points(monkeypatch, registry.PROFILES, "rig-6212", "rigprofile:PATH")
    refresh()
    try:
        assert "RIG-6212" in module_names()
        vm = VirtualModule("rig-6212")
        assert vm.profile.name == "RIG-6212" and vm.profile.firmware_version == "6212V999"
        assert vm.request(6, 4, 0).value == load_profile("TMCM-6212").axis_parameters[4].default  # extends
    finally:
        registry.of(registry.PROFILES).forget("rig-6212")
        refresh()


def test_a_third_party_engine_drives_a_profile(monkeypatch, tmp_path):
    """A profile whose `[module] engine` names an engine a distribution registers gets it."""
    (tmp_path / "myengine.py").write_text(textwrap.dedent("""\
        from opentmcl.motion.linear import LinearRampEngine

        class SlowEngine(LinearRampEngine):
            pass
        """))
    monkeypatch.syspath_prepend(str(tmp_path))
    fake_entry_points(monkeypatch, registry.ENGINES, "slow", "myengine:SlowEngine")
    try:
        assert "slow" in engine_names()
        assert type(make_engine("slow")).__name__ == "SlowEngine"
    finally:
        registry.of(registry.ENGINES).forget("slow")


def test_a_third_party_endpoint_is_served_by_serve(tmp_path):
    """`opentmcl serve --endpoint NAME:SPEC` builds what a distribution's factory answers (here an
    endpoint that writes the spec to a file when started), through a real subprocess."""
    pkg = tmp_path / "site"
    pkg.mkdir()
    (pkg / "myendpoint.py").write_text(textwrap.dedent("""\
        from pathlib import Path

        class Marker:
            url = "marker://here"
            def __init__(self, spec):
                self.spec = spec
            def start(self):
                Path(self.spec).write_text("started")
            def stop(self):
                Path(self.spec).write_text("stopped")

        def open_endpoint(bus, spec, options):
            return Marker(spec)
        """))
    dist = pkg / "myendpoint-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: myendpoint\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text("[opentmcl.endpoints]\nmarker = myendpoint:open_endpoint\n")
    marker = tmp_path / "marker.txt"
    env = {"PYTHONPATH": f"{pkg}:{ROOT / 'src'}", "PATH": "/usr/bin:/bin"}
    proc = subprocess.Popen([sys.executable, "-m", "opentmcl", "serve", "--module", "TMCM-6212",
                             "--endpoint", f"marker:{marker}"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env=env, text=True)
    try:
        out = ""
        while "Press Ctrl-C" not in out:
            line = proc.stdout.readline()
            assert line, proc.stderr.read()
            out += line
        assert "endpoint marker://here" in out and marker.read_text() == "started"
    finally:
        proc.terminate()
        proc.wait(30)
    assert marker.read_text() == "stopped"


def test_a_bad_endpoint_name_is_one_line_and_exit_2():
    run = subprocess.run([sys.executable, "-m", "opentmcl", "serve", "--module", "TMCM-6212", "--endpoint",
                          "fieldbus:x"], capture_output=True, text=True, timeout=60)
    assert run.returncode == 2
    assert run.stderr.count("\n") == 1 and "unknown endpoint 'fieldbus'" in run.stderr


def test_endpoint_options_reach_the_built_in_factories():
    from opentmcl.server.bus import ModuleBus

    bus = ModuleBus([VirtualModule("TMCM-6212")])
    tcp = make("tcp", bus, "127.0.0.1:0", EndpointOptions(max_clients=7, idle_timeout=5.0))
    assert (tcp.max_clients, tcp.idle_timeout, tcp.host) == (7, 5.0, "127.0.0.1")
