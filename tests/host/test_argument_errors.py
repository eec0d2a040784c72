"""Issue 11 problem 6: every argument error of the host library is a TmclError with a one-line
message, and keeps the built-in class plain Python code would raise (docs/host.md "Errors").

The ranges come from the frame (TMCM-6212 manual 3.1: address, command, type and motor/bank are
one byte each, the value four bytes) and from the profile (manual 1: the TMCM-6212 has six axes,
0..5). Each case is the last valid value's neighbour: the first invalid one.
"""
import math
import subprocess
import sys

import pytest

import opentmcl
from opentmcl.host import Client, profile_for_version, units
from opentmcl.host.errors import (
    AxisNumberError,
    TmclConnectionError,
    TmclError,
    TmclTypeError,
    TmclValueError,
    UnknownAttributeError,
    UnknownParameterError,
)
from opentmcl.host.loader import Loader, LoaderError
from opentmcl.host.transports.inprocess import InProcessTransport, RealClock, VirtualClock
from opentmcl.host.transports.serial import SerialTransport
from opentmcl.host.transports.tcp import TcpTransport


@pytest.fixture
def m():
    module = opentmcl.connect("sim://TMCM-6212")
    yield module
    module.close()


def refused(call, error, builtin):
    """`call()` raises `error`, which is a TmclError and a `builtin`, with a one-line message."""
    with pytest.raises(error) as info:
        call()
    assert isinstance(info.value, TmclError) and isinstance(info.value, builtin)
    text = str(info.value)
    assert text and "\n" not in text
    return text


def test_axis_index_past_the_last_axis(m):
    """Manual 1: six axes 0..5. ``axes[5]`` is the last one; ``axes[6]`` is an IndexError (as a
    list's) and a TmclError naming the range; ``axes[-7]`` too; ``axes[-1]`` is axis 5."""
    assert m.axes[5].number == 5 and m.axes[-1].number == 5
    assert "0..5" in refused(lambda: m.axes[6], AxisNumberError, IndexError)
    refused(lambda: m.axes[-7], AxisNumberError, IndexError)
    refused(lambda: m[6], AxisNumberError, IndexError)
    refused(lambda: m.axis(6), AxisNumberError, KeyError)  # earlier code caught KeyError
    refused(lambda: m.axes["0"], TmclTypeError, TypeError)
    assert [a.number for a in m.axes[4:]] == [4, 5]


@pytest.mark.parametrize("value, error, builtin", [
    (2**32, TmclValueError, ValueError),       # 2**32 - 1 is the last value four bytes carry
    (-(2**31) - 1, TmclValueError, ValueError),
    (2**40, TmclValueError, ValueError),
    (1.5, TmclTypeError, TypeError),
    ("51200", TmclTypeError, TypeError),
    (None, TmclTypeError, TypeError),
])
def test_values_that_do_not_fit_the_frame(m, value, error, builtin):
    """Manual 3.1: the value is four bytes. SAP 4 takes 2**32 - 1 into the frame; one more is
    refused before anything is sent."""
    refused(lambda: m.axes[0].set(4, value), error, builtin)
    refused(lambda: m.axes[0].move_to(value), error, builtin)


def test_bytes_of_the_frame(m):
    """Manual 3.1: command, type and motor/bank are one byte: 255 is the last, 256 the first
    refused; a float is a type error."""
    refused(lambda: m.request(256), TmclValueError, ValueError)
    refused(lambda: m.request(10, 256), TmclValueError, ValueError)
    refused(lambda: m.request(10, 66, 256), TmclValueError, ValueError)
    refused(lambda: m.axes[0].set_coordinate(1.5, 0), TmclTypeError, TypeError)
    refused(lambda: m.client.module(256), TmclValueError, ValueError)
    refused(lambda: m.client.send_raw(b"\x01\x0a"), TmclValueError, ValueError)


def test_names_and_types_of_parameters(m):
    """Names come from the profile (manual 4: axis parameters); an unknown one is a KeyError."""
    refused(lambda: m.axes[0].get("no_such_parameter"), UnknownParameterError, KeyError)
    refused(lambda: m.axes[0].set(256, 0), UnknownParameterError, KeyError)
    refused(lambda: m.axes[0].get(None), TmclTypeError, TypeError)
    refused(lambda: m.axes[0].get(4.0), TmclTypeError, TypeError)
    refused(lambda: m.get_global("no_such_parameter"), UnknownParameterError, KeyError)
    refused(lambda: m.axes[0].rotate("fast"), TmclTypeError, TypeError)
    refused(lambda: m.set_output(0, "1"), TmclTypeError, TypeError)
    refused(lambda: m.download_program([(1, 2)]), TmclValueError, ValueError)
    refused(lambda: m.wait_position_reached(0), TmclValueError, ValueError)
    refused(lambda: opentmcl.connect("sim://TMCM-6212", profile=6212), TmclTypeError, TypeError)
    refused(lambda: opentmcl.connect("sim://TMCM-6212", host_address="2"), TmclTypeError, TypeError)


BAD_TIMEOUTS = [(-1, TmclValueError), (0, TmclValueError), (math.nan, TmclValueError),
                (math.inf, TmclValueError), ("5", TmclTypeError), (True, TmclTypeError)]


@pytest.mark.parametrize("timeout, error", BAD_TIMEOUTS, ids=["-1", "0", "nan", "inf", "str", "bool"])
def test_timeouts_must_be_finite_and_positive(m, timeout, error):
    """A timeout bounds a wait: -1, 0, NaN and inf cannot (docs/host.md). Refused everywhere a
    timeout is accepted, before anything is sent."""
    builtin = ValueError if error is TmclValueError else TypeError
    for call in (
        lambda: opentmcl.connect("sim://TMCM-6212", timeout=timeout),
        lambda: opentmcl.host.open_bus("sim://TMCM-6212", timeout=timeout),
        lambda: Client(InProcessTransport(m.client.transport.modules), timeout=timeout),
        lambda: m.request(10, 66, 0, timeout=timeout),
        lambda: m.wait_position_reached(1, timeout=timeout),
        lambda: m.axes[0].move_to(0, wait=True, timeout=timeout),
        lambda: m.axes[0].wait_until_reached(timeout=timeout),
        lambda: m.axes[0].wait_until_reached(poll=timeout),
        lambda: m.axes[0].reference_search(wait=True, timeout=timeout),
        lambda: Loader(m, timeout=timeout),
        lambda: Loader(m).wait_stopped(timeout),
        lambda: TcpTransport("127.0.0.1", 1, connect_timeout=timeout),
        lambda: VirtualClock(timeout),
        lambda: RealClock(timeout),
    ):
        refused(call, error, builtin)


def test_smallest_timeout_is_accepted(m):
    """The edge: any positive finite timeout is valid; a move that cannot finish in it times out."""
    assert m.request(10, 66, 0, timeout=1e-9).value == 1
    m.axes[0].set("max_positioning_speed", 100)
    with pytest.raises(opentmcl.host.TmclTimeout):
        m.axes[0].move_to(100000, wait=True, timeout=0.01)


@pytest.mark.parametrize("seconds, error", [(-1, TmclValueError), (math.nan, TmclValueError),
                                            (math.inf, TmclValueError), ("1", TmclTypeError)])
def test_sleep_is_finite_and_not_negative(m, seconds, error):
    refused(lambda: m.sleep(seconds), error, ValueError if error is TmclValueError else TypeError)
    m.sleep(0)


@pytest.mark.parametrize("query", ["-1", "0", "nan", "inf"])
def test_url_timeouts(query):
    """The timeout keys of module URLs (tcp:// connect_timeout, sim:// step) are refused the same
    way, as connection errors naming the key (docs/endpoints.md)."""
    for url, key in ((f"tcp://127.0.0.1:1?connect_timeout={query}", "connect_timeout"),
                     (f"sim://TMCM-6212?step={query}", "step")):
        with pytest.raises(TmclConnectionError, match=key):
            opentmcl.connect(url)


def test_units_raise_typed_errors():
    """Manual 6.5: microstep resolution codes 0..8; a full step resolution must be positive; values
    must be finite numbers."""
    refused(lambda: units.rps_to_pps(1, 9), TmclValueError, ValueError)
    refused(lambda: units.rps_to_pps(1, 8, 0), TmclValueError, ValueError)
    refused(lambda: units.rps_to_pps(math.nan), TmclValueError, ValueError)
    refused(lambda: units.pps_to_tmc5130_velocity(math.inf), TmclValueError, ValueError)
    refused(lambda: units.pps_to_tmc429_velocity(1, 14), TmclValueError, ValueError)  # 13 is the last
    refused(lambda: units.pps2_to_tmc429_accel(math.nan, 1, 1), TmclValueError, ValueError)
    assert units.rps_to_pps(1, 8) == 51200  # manual 6.5: 51200 pps = 1 rps at 256 microsteps


def test_loader_and_debugger_arguments(m):
    from opentmcl.host.debugger import DebugError, Debugger, parse_watch

    refused(lambda: Loader(object()), TmclTypeError, TypeError)
    refused(lambda: Loader(m, address=256), TmclValueError, ValueError)
    refused(lambda: Loader(m).read(0, "2"), TmclTypeError, TypeError)
    refused(lambda: Loader(m).read_one("0"), TmclTypeError, TypeError)
    for program in ([(1, 2, 3, "x")], 5, b"\x01\x02\x03"):  # a binary image is 8-byte records
        with pytest.raises(LoaderError):
            Loader(m).download(program)
    debugger = Debugger(Loader(m))
    refused(lambda: debugger.address("no_label"), DebugError, ValueError)
    refused(lambda: debugger.address(5), TmclTypeError, TypeError)
    refused(lambda: debugger.step("1"), TmclTypeError, TypeError)
    refused(lambda: debugger.run_to({1}, max_steps="9"), TmclTypeError, TypeError)
    refused(lambda: debugger.cont(max_seconds=math.nan), TmclValueError, ValueError)
    refused(lambda: parse_watch("var256"), DebugError, ValueError)  # user variables are bytes (3.1)
    refused(lambda: parse_watch(5), TmclTypeError, TypeError)


def test_attribute_access_to_parameters(m):
    """``axis.params.NAME``: an unknown name is an AttributeError (hasattr works) and a TmclError."""
    assert m.axes[0].params.actual_position == 0               # GAP 1, 0 (manual 3.6.6)
    refused(lambda: m.axes[0].params.no_such_parameter, UnknownAttributeError, AttributeError)
    refused(lambda: m.globals.no_such_parameter, UnknownAttributeError, AttributeError)
    assert not hasattr(m.axes[0].params, "no_such_parameter")
    refused(lambda: setattr(m.axes[0].params, "max_positioning_speed", "fast"), TmclTypeError, TypeError)


def test_constructors_and_transports(m):
    refused(lambda: Client(None), TmclTypeError, TypeError)
    refused(lambda: Client(m.client.transport, address="1"), TmclTypeError, TypeError)
    refused(lambda: Client(m.client.transport, host_address=256), TmclValueError, ValueError)
    refused(lambda: InProcessTransport([]), TmclValueError, ValueError)
    refused(lambda: InProcessTransport(m.client.transport.modules, clock="wall"), TmclValueError, ValueError)
    refused(lambda: SerialTransport(None), TmclTypeError, TypeError)
    refused(lambda: profile_for_version(6212), TmclTypeError, TypeError)
    refused(lambda: m.get_global(66, bank="0"), TmclTypeError, TypeError)


SERVE_DUPLICATE = "module addresses must be distinct on one bus, got [1, 1]"


def test_two_modules_at_one_address_refused_as_serve_refuses_them():
    """Manual 3.1: the address byte selects the module, so two modules at one address would both
    answer. `opentmcl serve` refuses it; ``sim://`` gives the same message from the same rule."""
    done = subprocess.run([sys.executable, "-m", "opentmcl", "serve", "--module", "TMCM-6212", "--address", "1",
                           "--module", "TMCM-6212", "--address", "1", "--tcp", "127.0.0.1:0"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr.strip().endswith(SERVE_DUPLICATE) and done.stderr.count("\n") == 1
    with pytest.raises(TmclConnectionError) as info:
        opentmcl.connect("sim://TMCM-6212@1,TMCM-6212@1")
    assert str(info.value).endswith(SERVE_DUPLICATE)
    with pytest.raises(TmclConnectionError, match=r"distinct on one bus, got \[2, 2\]"):
        opentmcl.host.open_bus("sim://TMCM-6212@2,PD86-1180@2")
    bus = opentmcl.host.open_bus("sim://TMCM-6212@1,TMCM-6212@2")  # the edge: distinct is fine
    assert bus.module(2, "TMCM-6212").get_global(66) == 2     # GGP 66 (manual 3.6.8)
    bus.close()


def test_sim_address_range_is_the_range_of_serve():
    """GP66 is 1..255 (manual 5.1): serve refuses 0 and 256; so does sim://."""
    for bad in (0, 256):
        with pytest.raises(TmclConnectionError, match=r"must be 1\.\.255"):
            opentmcl.connect(f"sim://TMCM-6212@{bad}")
    opentmcl.connect("sim://TMCM-6212@255").close()
