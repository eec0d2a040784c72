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

Faults (docs/faults.md "Testing host code"): ``@pytest.mark.tmcl_faults([fault, ...], seeds=N)``
runs the test once per fault (a fault table, a list of tables armed together, a fault file) and
seed, each time on a fresh module whose link and firmware fail as described; ``.faults`` is the
armed plan (trigger a named fault, read what fired). A failure report names the faults, what
fired and the seed, and how to repeat the run (``--tmcl-fault-seed``).

Through the entry point this module is loaded into every pytest run of the environment, so it is
kept inert: importing it loads the host library only (no firmware, endpoints or third-party
packages), registers one option, one ini value and the marker, and builds a virtual module only
for a test that asks for ``tmcl_module`` (docs/pytest-plugin.md "Enabling it").
"""
from __future__ import annotations

import os
from collections.abc import Callable, Generator, Iterator
from typing import TYPE_CHECKING, Any

import pytest

from .host.client import Client
from .host.errors import TmclError, TmclValueError, check_int, check_seconds, check_timeout
from .host.module import Module

DEFAULT_MODULE = "TMCM-6212"
MARKER = "tmcl_module"
FAULTS_MARKER = "tmcl_faults"
_OPTIONS = ("address", "eeprom", "clock", "timeout", "host_address")
_FAULT_OPTIONS = ("seeds", "seed")

if TYPE_CHECKING:
    from .capture import ReplayReport
    from .faults import FaultBoard, FaultPlan
    from .firmware.vm import VirtualModule
    from .host.transports.inprocess import InProcessTransport


class TmclModule(Module):
    """A host `Module` on an in-process `VirtualModule`, with control over its virtual time."""

    def __init__(self, vm: VirtualModule, *, address: int, clock: str = "virtual", timeout: float = 5.0,
                 host_address: int = 2, faults: FaultPlan | None = None) -> None:
        from .sim import with_faults

        self.vm = vm
        self.transport: InProcessTransport = with_faults([vm], faults or _no_faults(), clock)
        self.faults: FaultBoard | None = self.transport.faults
        """The armed fault plan (None without one): ``faults.trigger(name)``, ``faults.log``."""
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


def _no_faults() -> FaultPlan:
    from .faults import FaultPlan

    return FaultPlan()


def make_tmcl_module(name: str = DEFAULT_MODULE, *, address: int = 1, eeprom: str | os.PathLike[str] | None = None,
                     clock: str = "virtual", timeout: float = 5.0, host_address: int = 2,
                     faults: object = None) -> TmclModule:
    """What the fixture builds; usable without pytest. KeyError for an unknown module name; the host
    library's typed errors for bad arguments: TmclValueError (also a ValueError) for an address
    outside 1..255 (the rule of `opentmcl serve`), a timeout that is not finite and > 0 or an
    unknown clock policy, TmclTypeError (also a TypeError) for an argument of the wrong type;
    `faults` (a fault plan, file, table or list of tables, docs/faults.md): FaultError if malformed."""
    from .faults import load_plan
    from .firmware.vm import VirtualModule
    from .modules.addresses import address_error

    reason = address_error([check_int(address, "module address")])
    if reason is not None:
        raise TmclValueError(reason)
    timeout = check_timeout(timeout)
    plan = load_plan(faults)
    vm = VirtualModule(name, address=address, eeprom=eeprom)
    try:
        return TmclModule(vm, address=address, clock=clock, timeout=timeout, host_address=host_address,
                          faults=plan)
    except BaseException:
        vm.close()
        raise


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("opentmcl", "OpenTMCL virtual modules")
    group.addoption("--tmcl-module", dest="tmcl_module", default=None, metavar="NAME",
                    help="module of the tmcl_module fixture when a test has no tmcl_module marker "
                         f"(default {DEFAULT_MODULE}; e.g. PD86-1180, PD28-1021)")
    group.addoption("--tmcl-fault-seed", dest="tmcl_fault_seed", default=None, type=int, metavar="N",
                    help="first seed of the tmcl_faults marker's runs (default: the marker's seed=, else a "
                         "new one; a failure report prints it)")
    parser.addini("tmcl_module", help="default module of the tmcl_module fixture", default=None)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        "tmcl_module(name, *, address=1, eeprom=None, clock='virtual', timeout=5.0, host_address=2): "
        "the virtual module that the tmcl_module fixture gives this test (opentmcl)")
    config.addinivalue_line(
        "markers",
        "tmcl_faults(faults, *, seeds=1, seed=None): run the test once per fault and seed, the "
        "tmcl_module's link and firmware failing as described (opentmcl, docs/faults.md)")


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
def tmcl_fault_case(request: pytest.FixtureRequest) -> FaultCase | None:
    """The faults of this run of a ``tmcl_faults`` test (None for other tests)."""
    return getattr(request, "param", None)


@pytest.fixture
def tmcl_module(request: pytest.FixtureRequest, tmcl_fault_case: FaultCase | None) -> Iterator[TmclModule]:
    """A virtual TMCL module behind the host `Module` API, in virtual time (opentmcl)."""
    from .firmware.eeprom import EepromError

    name, kwargs = _spec(request)
    if tmcl_fault_case is not None:
        kwargs["faults"] = tmcl_fault_case.plan
    error: str | None = None
    try:
        module = make_tmcl_module(name, **kwargs)
    except (KeyError, ValueError, EepromError, TmclError) as exc:
        error = f"tmcl_module: {exc.args[0] if exc.args else exc}"
    if error:  # failed outside the except block: one line, no "During handling of..." echo
        pytest.fail(error, pytrace=False)
    if tmcl_fault_case is not None:
        request.node.stash[_RUN] = (tmcl_fault_case, module.faults)
    try:
        yield module
    finally:
        module.close()


# --- faults: one run per fault and seed (docs/faults.md "Testing host code") ---------------------

class FaultCase:
    """One run of a ``tmcl_faults`` test: its faults, its seed and how to repeat it."""

    def __init__(self, plan: FaultPlan, label: str, seed: int, first: int) -> None:
        self.plan = plan.with_seed(seed)
        self.label = label
        self.seed = seed
        self.first = first
        """The first seed of the test's runs (--tmcl-fault-seed repeats them)."""

    def __repr__(self) -> str:
        return f"{self.label} (seed {self.seed})"


_RUN = pytest.StashKey[tuple]()
_FIRST_SEED = pytest.StashKey[int]()


def _case_label(item: object, plan: FaultPlan) -> str:
    if isinstance(item, (str, os.PathLike)):
        return os.path.splitext(os.path.basename(os.fspath(item)))[0]
    return "+".join(f.label for f in plan.faults) or "none"


def _fault_cases(marker: pytest.Mark, first: int) -> list[FaultCase]:
    from .faults import FaultError, load_plan

    if len(marker.args) != 1 or not isinstance(marker.args[0], (list, tuple)):
        raise FaultError(f"@pytest.mark.{FAULTS_MARKER} takes one list of faults, got {marker.args!r}")
    unknown = sorted(set(marker.kwargs) - set(_FAULT_OPTIONS))
    if unknown:
        raise FaultError(f"@pytest.mark.{FAULTS_MARKER}: unknown option(s) {', '.join(unknown)}; "
                         f"known: {', '.join(_FAULT_OPTIONS)}")
    seeds = marker.kwargs.get("seeds", 1)
    if isinstance(seeds, bool) or not isinstance(seeds, int) or not 1 <= seeds <= 1000:
        raise FaultError(f"@pytest.mark.{FAULTS_MARKER}: seeds must be 1..1000, got {seeds!r}")
    cases = []
    for i, item in enumerate(marker.args[0]):
        plan = load_plan(item)
        cases += [FaultCase(plan, _case_label(item, plan), first + 1000 * i + n, first) for n in range(seeds)]
    return cases


def _first_seed(config: pytest.Config, marker: pytest.Mark) -> int:
    option = config.getoption("tmcl_fault_seed", None)
    if option is not None:
        return int(option)
    if marker.kwargs.get("seed") is not None:
        return int(marker.kwargs["seed"])
    if _FIRST_SEED not in config.stash:
        from .faults import new_seed

        config.stash[_FIRST_SEED] = new_seed()
    return config.stash[_FIRST_SEED]


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    marker = metafunc.definition.get_closest_marker(FAULTS_MARKER)
    if marker is None or "tmcl_fault_case" not in metafunc.fixturenames:
        return
    from .faults import FaultError

    error: str | None = None
    try:
        cases = _fault_cases(marker, _first_seed(metafunc.config, marker))
    except FaultError as exc:
        error = f"{metafunc.definition.nodeid}: {exc}"
    if error:
        pytest.fail(error, pytrace=False)
    seeds = marker.kwargs.get("seeds", 1)
    ids = [f"{c.label}-s{n % seeds}" if seeds > 1 else c.label for n, c in enumerate(cases)]
    metafunc.parametrize("tmcl_fault_case", cases, ids=ids, indirect=True)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Generator[None, pytest.TestReport,
                                                                                           pytest.TestReport]:
    report = yield
    run = item.stash.get(_RUN, None)
    if run is not None and report.failed:
        case, board = run
        fired = [f.text() for f in board.log.since(max(0, len(board.log) - 20))] if board is not None else []
        report.sections.append(("opentmcl faults", "\n".join([
            f"faults: {case.label}; seed {case.seed}",
            f"repeat: pytest '{item.nodeid}' --tmcl-fault-seed {case.first}",
            "fired:" if fired else "fired: nothing", *(f"  {line}" for line in fired)])))
    return report


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
