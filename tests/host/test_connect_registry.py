"""The transport registry: `connect` finds transports by URL scheme (docs/architecture.md
"Extension points"), filled by the layers above the host library or by installed entry points."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from opentmcl import VirtualModule, registry
from opentmcl.host import connect, register_transport, transport_schemes
from opentmcl.host.errors import TmclConnectionError, TmclValueError
from opentmcl.host.transports.inprocess import InProcessTransport
from opentmcl.host.transports.serial import register_port_handler


@pytest.fixture(autouse=True)
def _registrations_stay_in_the_test(monkeypatch):
    for group in (registry.TRANSPORTS, registry.SERIAL_URL_HANDLERS):
        reg = registry.of(group)
        monkeypatch.setattr(reg, "_targets", dict(reg._targets))


def test_a_registered_factory_opens_its_scheme():
    """A factory gets the split URL; the module behind it answers GGP 66 with its address
    (TMCM-6212 manual 3.6.8) and command 136 with its version (manual 3.6.36)."""
    seen = []

    def open_bench(url):
        seen.append((url.scheme, url.netloc))
        return InProcessTransport(VirtualModule("PD86-1180", address=4))

    register_transport("Bench-Rig", open_bench)
    m = connect("bench-rig://left", address=4)
    try:
        assert m.get_global(66) == 4 and m.firmware_version() == "1180V445"
    finally:
        m.close()
    assert seen == [("bench-rig", "left")] and "bench-rig" in transport_schemes()


def test_a_lazy_reference_is_imported_on_first_use():
    """A "package.module:attribute" string is resolved when a URL uses the scheme."""
    register_transport("twin", "opentmcl.sim:open_sim")
    m = connect("twin://TMCM-6212")
    try:
        assert m.get_global(66) == 1
    finally:
        m.close()


@pytest.mark.parametrize("scheme", ["a", "a+b-c.d", "X9"])
def test_a_url_scheme_is_a_valid_name(scheme):
    """RFC 3986 3.1: scheme = ALPHA *( ALPHA / DIGIT / "+" / "-" / "." ); the shortest is one letter."""
    register_transport(scheme, "opentmcl.sim:open_sim")
    assert scheme.lower() in transport_schemes()


@pytest.mark.parametrize("scheme", ["", "1a", "a_b", "a b", "tcp://", 7])
def test_a_bad_scheme_or_factory_is_refused(scheme):
    with pytest.raises(TmclValueError):
        register_transport(scheme, "opentmcl.sim:open_sim")


@pytest.mark.parametrize("factory", [42, "no-colon", "opentmcl.sim:", ":open_sim"])
def test_a_factory_must_be_callable_or_a_reference(factory):
    with pytest.raises(TmclValueError):
        register_transport("fine", factory)


def test_unknown_scheme_lists_the_known_ones():
    with pytest.raises(TmclConnectionError, match="unknown URL scheme 'nowhere'") as err:
        connect("nowhere://x")
    for scheme in ("sim://", "tcp://", "serial://", "can://"):
        assert scheme in str(err.value)


def test_a_reference_that_does_not_load_is_a_connection_error():
    register_transport("broken", "opentmcl.no_such_module:open")
    with pytest.raises(TmclConnectionError, match="broken:// transport is not available"):
        connect("broken://x")


def test_a_factory_that_returns_no_transport_is_a_connection_error():
    register_transport("notransport", lambda url: object())
    with pytest.raises(TmclConnectionError, match="not a Transport"):
        connect("notransport://x")


def test_a_port_handler_runs_before_pyserial_opens_its_url():
    """The serial transport runs the hook of a pyserial URL scheme first (the way the root package
    makes opentmcl:// known); pyserial then refuses the unknown protocol with a typed error."""
    calls = []
    register_port_handler("hooktest", lambda: calls.append(1))
    with pytest.raises(TmclConnectionError, match="cannot open serial port"):
        connect("serial://?port=hooktest://x")
    assert calls == [1]
    with pytest.raises(TmclValueError):
        register_port_handler("hooktest", 3)


def test_an_installed_entry_point_adds_a_scheme(tmp_path):
    """A third-party distribution (a real dist-info on sys.path) registers ``plug`` in the
    ``opentmcl.transports`` entry-point group; it is imported only when a URL uses it."""
    (tmp_path / "plug_transport").mkdir()
    (tmp_path / "plug_transport" / "__init__.py").write_text(textwrap.dedent("""
        from opentmcl import VirtualModule
        from opentmcl.host.transports.inprocess import InProcessTransport

        def open_plug(url):
            return InProcessTransport(VirtualModule("PD86-1180", address=1))
        """))
    info = tmp_path / "plug_transport-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: plug-transport\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[opentmcl.transports]\nplug = plug_transport:open_plug\n")
    code = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(tmp_path)!r})
        from opentmcl.host import connect
        from opentmcl.host.errors import TmclConnectionError
        m = connect("sim://TMCM-6212"); m.close()
        print("plug_transport" in sys.modules)
        try:
            connect("nowhere://x")
        except TmclConnectionError as exc:
            print("plug://" in str(exc))
        m = connect("plug://anything")
        print(m.firmware_version()); m.close()
        """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         timeout=60).stdout.split()
    assert out == ["False", "True", "1180V445"]
