"""pytest plugin: a virtual TMCL module for your own test suite (docs/pytest-plugin.md).

Installed with opentmcl it is found through the ``pytest11`` entry point; without it, enable
it with ``-p opentmcl.pytest_plugin`` or ``pytest_plugins = ["opentmcl.pytest_plugin"]``.

    @pytest.mark.tmcl_module("PD86-1180", address=3)
    def test_move(tmcl_module):
        tmcl_module[0].move_to(1000, wait=True)     # waiting lets virtual time pass
        tmcl_module.advance(0.5)                    # half a virtual second more
        assert tmcl_module.vm.axes[0].engine.position == 1000

The fixture is a host `Module` (the same API as ``opentmcl.connect("sim://...")``) talking to a
`VirtualModule` in this process, plus:

- ``.vm``: the virtual module itself (its parameters, axes, I/O and world);
- ``.advance(seconds)``: let virtual time pass (motion, timers, command-138 events);
- ``.time``: virtual seconds since power-up;
- ``.transport``: the in-process transport.

Which module: the ``tmcl_module`` marker of the test (or its class/module), else the
``--tmcl-module NAME`` option, else the ``tmcl_module`` ini value, else TMCM-6212.

Through the entry point this module is loaded into every pytest run of the environment, so it is
kept inert: importing it loads the host library only (no firmware, endpoints or third-party
packages), registers one option, one ini value and the marker, and builds a virtual module only
for a test that asks for ``tmcl_module`` (docs/pytest-plugin.md "Enabling it").
"""
from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

import pytest

from .host.client import Client
from .host.errors import TmclError, TmclValueError, check_int, check_seconds, check_timeout
from .host.module import Module

DEFAULT_MODULE = "TMCM-6212"
MARKER = "tmcl_module"
_OPTIONS = ("address", "eeprom", "clock", "timeout", "host_address")

if TYPE_CHECKING:
    from .capture import ReplayReport
    from .firmware.vm import VirtualModule
    from .host.transports.inprocess import InProcessTransport


class TmclModule(Module):
    """A host `Module` on an in-process `VirtualModule`, with control over its virtual time."""

    def __init__(self, vm: VirtualModule, *, address: int, clock: str = "virtual", timeout: float = 5.0,
                 host_address: int = 2) -> None:
        from .host.transports.inprocess import InProcessTransport

        self.vm = vm
        self.transport: InProcessTransport = InProcessTransport([vm], clock=clock)
        super().__init__(Client(self.transport, address=address, host_address=host_address,
                                timeout=timeout), address, vm.profile)

    def __repr__(self) -> str:
        return f"<TmclModule {self.vm.profile.name} at address {self.address}, t={self.time:g} s>"

    def advance(self, seconds: float) -> None:
        """Let `seconds` of virtual time pass (events such as command 138 replies are collected)."""
        self.transport.advance(check_seconds(seconds, "seconds to advance"))

    @property
    def time(self) -> float:
        """Virtual seconds since the module powered up."""
        return self.vm.time

    def close(self) -> None:
        """Close the transport and flush the module's EEPROM file (if it has one)."""
        self.client.close()
        self.vm.close()


def make_tmcl_module(name: str = DEFAULT_MODULE, *, address: int = 1, eeprom: str | os.PathLike[str] | None = None,
                     clock: str = "virtual", timeout: float = 5.0, host_address: int = 2) -> TmclModule:
    """What the fixture builds; usable without pytest. KeyError for an unknown module name; the host
    library's typed errors for bad arguments: TmclValueError (also a ValueError) for an address
    outside 1..255 (the rule of `opentmcl serve`), a timeout that is not finite and > 0 or an
    unknown clock policy, TmclTypeError (also a TypeError) for an argument of the wrong type."""
    from .firmware.vm import VirtualModule
    from .modules.addresses import address_error

    reason = address_error([check_int(address, "module address")])
    if reason is not None:
        raise TmclValueError(reason)
    timeout = check_timeout(timeout)
    vm = VirtualModule(name, address=address, eeprom=eeprom)
    try:
        return TmclModule(vm, address=address, clock=clock, timeout=timeout, host_address=host_address)
    except BaseException:
        vm.close()
        raise


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("opentmcl", "OpenTMCL virtual modules")
    group.addoption("--tmcl-module", dest="tmcl_module", default=None, metavar="NAME",
                    help="module of the tmcl_module fixture when a test has no tmcl_module marker "
                         f"(default {DEFAULT_MODULE}; e.g. PD86-1180, PD28-1021)")
    parser.addini("tmcl_module", help="default module of the tmcl_module fixture", default=None)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        "tmcl_module(name, *, address=1, eeprom=None, clock='virtual', timeout=5.0, host_address=2): "
        "the virtual module that the tmcl_module fixture gives this test (opentmcl)")


def _ini_module(config: pytest.Config) -> str | None:
    """The ini `tmcl_module`; a relative profile file path is relative to the ini file, as
    pytest's own path options are, so the suite runs from any directory."""
    from pathlib import Path

    from .modules.profile_file import looks_like_path

    name: str | None = config.getini("tmcl_module")
    if name and looks_like_path(name) and not Path(name).is_absolute() and config.inipath is not None:
        return str(Path(config.inipath).parent / name)
    return name


def _spec(request: pytest.FixtureRequest) -> tuple[str, dict[str, Any]]:
    """The module name and make_tmcl_module() keywords of this test (the marker's, as pytest gives them)."""
    marker = request.node.get_closest_marker(MARKER)
    config = request.config
    name = config.getoption("tmcl_module", None) or _ini_module(config) or DEFAULT_MODULE
    kwargs: dict[str, Any] = {}
    if marker is not None:
        if len(marker.args) > 1:
            pytest.fail(f"@pytest.mark.{MARKER} takes one module name, got {marker.args!r}", pytrace=False)
        if marker.args:
            name = marker.args[0]
        unknown = sorted(set(marker.kwargs) - set(_OPTIONS))
        if unknown:
            pytest.fail(f"@pytest.mark.{MARKER}: unknown option(s) {', '.join(unknown)}; "
                        f"known: {', '.join(_OPTIONS)}", pytrace=False)
        kwargs = dict(marker.kwargs)
    if not isinstance(name, str):
        pytest.fail(f"@pytest.mark.{MARKER}: the module name must be a string, got {name!r}", pytrace=False)
    return name, kwargs


@pytest.fixture
def tmcl_module(request: pytest.FixtureRequest) -> Iterator[TmclModule]:
    """A virtual TMCL module behind the host `Module` API, in virtual time (opentmcl)."""
    from .firmware.eeprom import EepromError

    name, kwargs = _spec(request)
    error: str | None = None
    try:
        module = make_tmcl_module(name, **kwargs)
    except (KeyError, ValueError, EepromError, TmclError) as exc:
        error = f"tmcl_module: {exc.args[0] if exc.args else exc}"
    if error:  # failed outside the except block: one line, no "During handling of..." echo
        pytest.fail(error, pytrace=False)
    try:
        yield module
    finally:
        module.close()


@pytest.fixture
def tmcl_replay() -> Callable[..., ReplayReport]:
    """Keep captures as regression tests (docs/capture.md): ``tmcl_replay("run.jsonl", "PD86-1180")``
    replays a capture against a fresh virtual module and fails the test listing every divergence.
    Takes the arguments of `opentmcl.replay` and returns its report."""
    from .capture import CaptureError, ReplayError, replay

    def check(capture: str | os.PathLike[str], module: str | os.PathLike[str] | None = None,
              **kwargs: Any) -> ReplayReport:  # replay()'s keywords, passed through
        error: str | None = None
        try:
            report = replay(capture, module, **kwargs)
        except (CaptureError, ReplayError) as exc:
            error = f"tmcl_replay: {exc}"
        if error:
            pytest.fail(error, pytrace=False)
        if not report.ok:
            pytest.fail(report.text(), pytrace=False)
        return report

    return check
