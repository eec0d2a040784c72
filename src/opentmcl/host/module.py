"""Module and Axis: a TMCL module seen through named parameters from its profile.

    m = opentmcl.connect("sim://TMCM-6212")
    m.axes[0].set("max_positioning_speed", 51200)   # SAP 4, 0, 51200 (TMCM-6212 manual 3.6.5)
    m.axes[0].move_to(10000, wait=True)               # 138 + MVP ABS, 0, 10000 (3.6.4, 3.6.35)
    m.axes[0].get("actual_position")                  # GAP 1, 0 (3.6.6)

Parameter names and numbers come from the module profile (opentmcl.modules),
chosen from the version string of command 136 or given explicitly. Values are
passed through unchanged: the module is the authority on ranges and access
and answers bad ones with a status code, which raises `TmclStatusError`.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import SupportsIndex, overload

from ..modules.names import NameIndex
from ..modules.names import norm as _norm
from ..modules.profile import IOPort, ModuleProfile, Param, load_profile, module_names
from ..protocol.frame import Reply
from ..protocol.opcodes import (
    ENTER_DOWNLOAD_MODE,
    EXIT_DOWNLOAD_MODE,
    GET_APPLICATION_STATUS,
    GET_FIRMWARE_VERSION,
    REQUEST_TARGET_REACHED_EVENT,
    RESET_APPLICATION,
    RESTORE_FACTORY_SETTINGS,
    RUN_APPLICATION,
    STEP_APPLICATION,
    STOP_APPLICATION,
    Op,
)
from . import units
from .client import (
    Answer,
    Client,
    VersionReply,
    check_address,
)
from .errors import (
    AxisNumberError,
    TmclError,
    TmclTimeout,
    TmclTypeError,
    TmclValueError,
    UnknownAttributeError,
    UnknownParameterError,
    check_int,
    check_timeout,
)

# Command numbers as plain ints, which `Client.request` keeps ready to send (TMCM-6212 manual 3.4.1).
_ROR, _ROL, _MST, _MVP = int(Op.ROR), int(Op.ROL), int(Op.MST), int(Op.MVP)
_SAP, _GAP, _STAP, _RSAP = int(Op.SAP), int(Op.GAP), int(Op.STAP), int(Op.RSAP)
_SGP, _GGP, _STGP, _RSGP = int(Op.SGP), int(Op.GGP), int(Op.STGP), int(Op.RSGP)
_RFS, _SIO, _GIO = int(Op.RFS), int(Op.SIO), int(Op.GIO)
_SCO, _GCO, _CCO = int(Op.SCO), int(Op.GCO), int(Op.CCO)
MVP_ABS, MVP_REL, MVP_COORD = 0, 1, 2
RFS_START, RFS_STOP, RFS_STATUS = 0, 1, 2
USER_VARIABLE_BANK = 2  # SGP/GGP bank 2: TMCL user variables (TMCM-6212 manual 5.3)
FACTORY_RESET_KEY = 1234  # command 137 value (manual 3.6.36)

MOTION_TIMEOUT = 60.0  # default seconds to wait for a move or a reference search
POLL_INTERVAL = 0.01  # seconds between status polls (one TMCL tick is 10 ms)


def _byte_number(kind: str, number: int) -> int:
    """A parameter or bank number: 0..255, the type or motor/bank byte of the frame (manual 3.1)."""
    if not 0 <= number <= 255:
        raise UnknownParameterError(f"{kind} number must be 0..255, got {number}")
    return number


def _raw_number(kind: str, key: object) -> int | None:
    """A parameter given by number passes through unchanged (0..255): the module decides."""
    if isinstance(key, int) and not isinstance(key, bool):
        return _byte_number(kind, key)
    return None


def _find(kind: str, key: str | int, lookup: Callable[[str | int], Param], names: NameIndex) -> Param:
    """The profile entry `key` names: a number, or our name, the manual's title or an alias such as
    PyTrinamic's ``MaxVelocity`` (modules/names.py); an unknown name lists close ones of both."""
    if isinstance(key, bool) or not isinstance(key, (int, str)):
        raise TmclTypeError(f"{kind} must be a name or a number, got {key!r}")
    try:
        return lookup(key)
    except KeyError:
        pass
    if isinstance(key, str):
        hint = names.suggest(key)
        more = f"; did you mean {', '.join(hint)}?" if hint else ""
        raise UnknownParameterError(f"unknown {kind} {key!r}{more}")
    raise UnknownParameterError(f"{kind} {key} is not defined in the module profile")


def profile_for_version(version: str) -> ModuleProfile:
    """The profile whose firmware version string (command 136 type 0) names the same module type.

    The string is the module number, "V" and the version digits (e.g. "6212V105", PD86-1180 manual
    4.6.39 "1180V1.30"); the module number before the "V" selects the profile.
    """
    if not isinstance(version, str):
        raise TmclTypeError(f"firmware version must be a string, got {version!r}")
    kind = version.strip().upper().partition("V")[0]
    exact = None
    for name in module_names():
        prof = load_profile(name)
        if prof.firmware_version == version:
            return prof
        if exact is None and prof.firmware_version.upper().partition("V")[0] == kind:
            exact = prof
    if exact is None:
        raise TmclError(f"no module profile for firmware version {version!r}; "
                        f"give the profile explicitly (known: {', '.join(module_names())})")
    return exact


class _Params:
    """Attribute access to parameters: ``axis.params.actual_position``; assignment sets."""

    _get: Callable[[str], int]
    _set: Callable[[str, int], None]
    _names: Callable[[], list[str]]

    def __init__(self, getter: Callable[[str], int], setter: Callable[[str, int], None],
                 names: Callable[[], list[str]]) -> None:
        object.__setattr__(self, "_get", getter)
        object.__setattr__(self, "_set", setter)
        object.__setattr__(self, "_names", names)

    def __getattr__(self, name: str) -> int:
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return self._get(name)
        except UnknownParameterError as exc:
            raise UnknownAttributeError(str(exc)) from None

    def __setattr__(self, name: str, value: int) -> None:
        try:
            self._set(name, value)
        except UnknownParameterError as exc:
            raise UnknownAttributeError(str(exc)) from None

    def __dir__(self) -> list[str]:
        return sorted(self._names())


class AxisList(list["Axis"]):
    """`Module.axes`: a list whose bad index is an `AxisNumberError` (an IndexError and a
    TmclError) naming the axes the module has."""

    def __init__(self, axes: Iterable[Axis], module_name: str) -> None:
        super().__init__(axes)
        self._module_name = module_name

    @overload
    def __getitem__(self, index: SupportsIndex) -> Axis: ...

    @overload
    def __getitem__(self, index: slice) -> list[Axis]: ...

    def __getitem__(self, index: SupportsIndex | slice) -> Axis | list[Axis]:
        if isinstance(index, slice):
            return super().__getitem__(index)
        if isinstance(index, bool) or not isinstance(index, int):
            raise TmclTypeError(f"axis index must be an int, got {type(index).__name__} {index!r}")
        try:
            return super().__getitem__(index)
        except IndexError:
            raise AxisNumberError(f"{self._module_name} has axes 0..{len(self) - 1}, not {index}") from None


def _check_poll(poll: float) -> float:
    return check_timeout(poll, "poll interval")


class Axis:
    """One motor of a module; parameters by name or number (axis parameters, TMCM-6212 manual 4)."""

    def __init__(self, module: Module, number: int):
        self.module = module
        self.number = number
        self.params = _Params(self.get, self.set, lambda: [p.name for p in self._all()])

    def __repr__(self) -> str:
        return f"<Axis {self.number} of {self.module!r}>"

    def _all(self) -> list[Param]:
        return list(self.module.profile.axis_parameters.values())

    def _req(self, command: int, type: int = 0, value: int = 0) -> Reply:
        return self.module.reply(command, type, self.number, value)

    # --- parameters -------------------------------------------------------------
    def param(self, name: str | int) -> Param:
        """The profile entry of an axis parameter (number, name, range, access, unit)."""
        prof = self.module.profile
        return _find("axis parameter", name, prof.axis_parameter, prof.axis_names)

    def _number(self, name: str | int) -> int:
        number = _raw_number("axis parameter", name)
        return self.param(name).number if number is None else number

    def get(self, name: str | int) -> int:
        """GAP <parameter>, <axis> (manual 3.6.6)."""
        return self._req(_GAP, self._number(name)).value

    def set(self, name: str | int, value: int) -> None:
        """SAP <parameter>, <axis>, <value> (manual 3.6.5)."""
        self._req(_SAP, self._number(name), value)

    def store(self, name: str | int) -> None:
        """STAP <parameter>, <axis>: store in EEPROM (PD86-1180 manual 4.6.7)."""
        self._req(_STAP, self._number(name))

    def restore(self, name: str | int) -> None:
        """RSAP <parameter>, <axis>: restore from EEPROM (PD86-1180 manual 4.6.8)."""
        self._req(_RSAP, self._number(name))

    @property
    def position(self) -> int:
        """Actual position (axis parameter 1) in microsteps."""
        return self.module.reply(_GAP, 1, self.number).value  # (`_req` inlined: the most polled read)

    @position.setter
    def position(self, value: int) -> None:
        self._req(_SAP, 1, value)

    @property
    def target_position(self) -> int:
        return self._req(_GAP, 0).value

    @property
    def actual_speed(self) -> int:
        return self._req(_GAP, 3).value

    @property
    def position_reached(self) -> bool:
        """Axis parameter 8: "always set when target position and actual position are equal"."""
        return self.module.reply(_GAP, 8, self.number).value != 0

    # --- motion -------------------------------------------------------------------
    def rotate(self, velocity: int) -> None:
        """ROR <axis>, v for v >= 0, else ROL <axis>, -v (manual 3.6.1, 3.6.2)."""
        check_int(velocity, "velocity")
        if velocity >= 0:
            self._req(_ROR, 0, velocity)
        else:
            self._req(_ROL, 0, -velocity)

    def rotate_right(self, velocity: int) -> None:
        self._req(_ROR, 0, velocity)

    def rotate_left(self, velocity: int) -> None:
        self._req(_ROL, 0, velocity)

    def stop(self) -> None:
        """MST <axis> (manual 3.6.3)."""
        self._req(_MST)

    def _move(self, type: int, value: int, wait: bool, timeout: float | None) -> None:
        if timeout is not None:
            check_timeout(timeout)
        if wait:
            self.module.request_position_reached_event(1 << self.number)
        self._req(_MVP, type, value)
        if wait:
            self.module.wait_position_reached(1 << self.number, MOTION_TIMEOUT if timeout is None else timeout)

    def move_to(self, position: int, *, wait: bool = False, timeout: float | None = None) -> None:
        """MVP ABS, <axis>, <position> (manual 3.6.4). With `wait`, block until the target is reached,
        using the position reached event of command 138 (manual 3.6.35)."""
        self._move(MVP_ABS, position, wait, timeout)

    def move_by(self, offset: int, *, wait: bool = False, timeout: float | None = None) -> None:
        """MVP REL, <axis>, <offset> (manual 3.6.4)."""
        self._move(MVP_REL, offset, wait, timeout)

    def move_to_coordinate(self, coordinate: int, *, wait: bool = False, timeout: float | None = None) -> None:
        """MVP COORD, <axis>, <coordinate> (manual 3.6.4)."""
        self._move(MVP_COORD, coordinate, wait, timeout)

    def wait_until_reached(self, timeout: float | None = None, poll: float = POLL_INTERVAL) -> None:
        """Poll axis parameter 8 (position reached flag) until it is set."""
        self.module._poll(lambda: self.position_reached, timeout, poll,
                          f"axis {self.number} did not reach its target position")

    def reference_search(self, *, wait: bool = False, timeout: float | None = None,
                         poll: float = POLL_INTERVAL) -> None:
        """RFS START, <axis> (manual 3.6.11); with `wait`, poll RFS STATUS until it reports 0."""
        if timeout is not None:
            check_timeout(timeout)
        _check_poll(poll)
        self._req(_RFS, RFS_START)
        if wait:
            self.module._poll(lambda: not self.reference_search_active(), timeout, poll,
                              f"reference search of axis {self.number} did not finish")

    def stop_reference_search(self) -> None:
        self._req(_RFS, RFS_STOP)

    def reference_search_active(self) -> bool:
        """RFS STATUS: 0 = no reference search active (manual 3.6.11)."""
        return self._req(_RFS, RFS_STATUS).value != 0

    # --- coordinates -----------------------------------------------------------
    def set_coordinate(self, coordinate: int, position: int) -> None:
        """SCO <coordinate>, <axis>, <position> (manual 3.6.22)."""
        self._req(_SCO, coordinate, position)

    def get_coordinate(self, coordinate: int) -> int:
        """GCO <coordinate>, <axis> (manual 3.6.23)."""
        return self._req(_GCO, coordinate).value

    def capture_coordinate(self, coordinate: int) -> None:
        """CCO <coordinate>, <axis> (manual 3.6.24)."""
        self._req(_CCO, coordinate)

    # --- units --------------------------------------------------------------------
    def _has(self, number: int) -> bool:
        return number in self.module.profile.axis_parameters

    def microstep_resolution(self) -> int:
        """Axis parameter 140 (0 = full step ... 8 = 256 microsteps)."""
        return self._req(_GAP, 140).value

    def fullstep_resolution(self) -> int:
        """Axis parameter 202 (full steps per round); 200 when the module has no such parameter."""
        return self._req(_GAP, 202).value if self._has(202) else 200

    def pps_to_rps(self, pps: float) -> float:
        return units.pps_to_rps(pps, self.microstep_resolution(), self.fullstep_resolution())

    def rps_to_pps(self, rps: float) -> int:
        return units.rps_to_pps(rps, self.microstep_resolution(), self.fullstep_resolution())

    def pps_to_rpm(self, pps: float) -> float:
        return units.pps_to_rpm(pps, self.microstep_resolution(), self.fullstep_resolution())

    def rpm_to_pps(self, rpm: float) -> int:
        return units.rpm_to_pps(rpm, self.microstep_resolution(), self.fullstep_resolution())

    def _divisors(self) -> tuple[int, int]:
        if not (self._has(153) and self._has(154)):
            raise TmclError(f"{self.module.profile.name} has no pulse/ramp divisors (axis parameters 153/154)")
        return self._req(_GAP, 154).value, self._req(_GAP, 153).value

    def velocity_to_pps(self, velocity: int) -> float:
        """TMC429 internal velocity (0..2047) -> pps with this axis's pulse divisor (PD86-1180 manual 5)."""
        return units.tmc429_velocity_to_pps(velocity, self._divisors()[0])

    def pps_to_velocity(self, pps: float) -> int:
        return units.pps_to_tmc429_velocity(pps, self._divisors()[0])

    def acceleration_to_pps2(self, a_max: int) -> float:
        """TMC429 internal acceleration -> pps² with this axis's pulse and ramp divisors."""
        pulse_div, ramp_div = self._divisors()
        return units.tmc429_accel_to_pps2(a_max, pulse_div, ramp_div)

    def pps2_to_acceleration(self, pps2: float) -> int:
        pulse_div, ramp_div = self._divisors()
        return units.pps2_to_tmc429_accel(pps2, pulse_div, ramp_div)


class Module:
    """One TMCL module at `address` on the bus served by `client`."""

    def __init__(self, client: Client, address: int | None = None,
                 profile: ModuleProfile | str | None = None):
        self.client = client
        self.address = client.address if address is None else check_address(address)
        if profile is not None and not isinstance(profile, (str, ModuleProfile)):
            raise TmclTypeError(f"profile must be a module name or a ModuleProfile, got {profile!r}")
        if isinstance(profile, str):
            try:
                profile = load_profile(profile)
            except KeyError as exc:
                raise UnknownParameterError(exc.args[0]) from None
        self._profile = profile
        self._axes: list[Axis] | None = None
        self.globals = _Params(self.get_global, self.set_global,
                               lambda: [p.name for p in self.profile.global_parameters.values()])

    def __repr__(self) -> str:
        name = self._profile.name if self._profile else "?"
        return f"<Module {name} at address {self.address}>"

    # --- identity --------------------------------------------------------------
    @property
    def profile(self) -> ModuleProfile:
        """The module profile, read from the version string (command 136) on first use."""
        if self._profile is None:
            self._profile = profile_for_version(self.firmware_version())
        return self._profile

    @property
    def name(self) -> str:
        return self.profile.name

    def firmware_version(self) -> str:
        """Command 136 type 0: the version string, e.g. "6212V105" (manual 3.6.36)."""
        reply = self.request(GET_FIRMWARE_VERSION, 0)
        if not isinstance(reply, VersionReply):  # pragma: no cover - Client guarantees it
            raise TmclError(f"unexpected reply to command 136: {reply!r}")
        return reply.text

    def firmware_version_binary(self) -> int:
        """Command 136 type 1: the version number in the value field (PD86-1180 manual 4.6.39)."""
        return self.reply(GET_FIRMWARE_VERSION, 1).value

    @property
    def axes(self) -> list[Axis]:
        if self._axes is None:
            self._axes = AxisList((Axis(self, i) for i in range(self.profile.axes)), self.profile.name)
        return self._axes

    def axis(self, number: int) -> Axis:
        axes = self.axes
        if isinstance(number, int) and not isinstance(number, bool) and 0 <= number < len(axes):
            return axes[number]
        raise AxisNumberError(f"{self.profile.name} has axes 0..{self.profile.axes - 1}, not {number!r}")

    def __getitem__(self, number: int) -> Axis:
        return self.axis(number)

    def __iter__(self) -> Iterator[Axis]:
        return iter(self.axes)

    # --- raw requests -----------------------------------------------------------
    def request(self, command: int, type: int = 0, motor: int = 0, value: int = 0, *,
                timeout: float | None = None) -> Answer:
        """Send one request to this module; see `Client.request`."""
        return self.client.request(command, type, motor, value, address=self.address, timeout=timeout)

    def request_many(self, requests: Sequence[tuple[int, int, int, int]], *,
                     timeout: float | None = None) -> list[Answer]:
        """Several ``(command, type, motor, value)`` requests to this module, answers in order;
        see `Client.request_many`."""
        return self.client.request_many(requests, address=self.address, timeout=timeout)

    def reply(self, command: int, type: int = 0, motor: int = 0, value: int = 0, *,
              timeout: float | None = None) -> Reply:
        """A request with a reply in the format of manual 3.2; see `Client.reply`."""
        return self.client.reply(command, type, motor, value, address=self.address, timeout=timeout)

    # --- global parameters and user variables (manual 3.6.7-3.6.10, 5) ------------
    def global_param(self, name: str | int, bank: int = 0) -> Param:
        prof = self.profile
        return _find("global parameter", name, lambda k: prof.global_parameter(k, bank), prof.global_names)

    def _gp(self, name: str | int, bank: int | None) -> tuple[int, int]:
        """(number, bank): a name implies its bank; a number goes to `bank` (default 0) unchanged."""
        if bank is not None:
            check_int(bank, "bank")
        number = _raw_number("global parameter", name)
        if number is not None:
            return number, _byte_number("bank", 0 if bank is None else bank)
        p = self.global_param(name)
        return p.number, (p.bank if p.bank is not None else (bank or 0))

    def get_global(self, name: str | int, bank: int | None = None) -> int:
        """GGP <parameter>, <bank> (manual 3.6.8). A name implies its bank."""
        number, bank = self._gp(name, bank)
        return self.reply(_GGP, number, bank).value

    def set_global(self, name: str | int, value: int, bank: int | None = None) -> None:
        """SGP <parameter>, <bank>, <value> (manual 3.6.7)."""
        number, bank = self._gp(name, bank)
        self.request(_SGP, number, bank, value)

    def store_global(self, name: str | int, bank: int | None = None) -> None:
        """STGP <parameter>, <bank> (manual 3.6.9)."""
        number, bank = self._gp(name, bank)
        self.request(_STGP, number, bank)

    def restore_global(self, name: str | int, bank: int | None = None) -> None:
        """RSGP <parameter>, <bank> (manual 3.6.10)."""
        number, bank = self._gp(name, bank)
        self.request(_RSGP, number, bank)

    def _var(self, index: int) -> int:
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < self.profile.user_variables:
            raise UnknownParameterError(f"user variable must be 0..{self.profile.user_variables - 1}, "
                                        f"got {index!r}")
        return index

    def get_variable(self, index: int) -> int:
        """GGP <index>, 2: TMCL user variable (manual 5.3)."""
        return self.reply(_GGP, self._var(index), USER_VARIABLE_BANK).value

    def set_variable(self, index: int, value: int) -> None:
        """SGP <index>, 2, <value>."""
        self.request(_SGP, self._var(index), USER_VARIABLE_BANK, value)

    def store_variable(self, index: int) -> None:
        """STGP <index>, 2: store a user variable in EEPROM (manual 3.6.9)."""
        self.request(_STGP, self._var(index), USER_VARIABLE_BANK)

    def restore_variable(self, index: int) -> None:
        """RSGP <index>, 2 (manual 3.6.10)."""
        self.request(_RSGP, self._var(index), USER_VARIABLE_BANK)

    # --- inputs and outputs (manual 3.6.12, 3.6.13) ------------------------------
    def _port(self, port: int | str, kind: str) -> IOPort:
        ports = [p for p in self.profile.io.values() if p.kind == kind]
        for p in ports:
            if p.port == port or (isinstance(port, str) and _norm(p.name) == _norm(port)):
                return p
        names = ", ".join(f"{p.name} ({p.port})" for p in ports) or "none"
        raise UnknownParameterError(f"{self.profile.name} has no {kind} port {port!r}; {kind} ports: {names}")

    def digital_input(self, port: int | str) -> int:
        """GIO <port>, <digital input bank> (bank 0 on the TMCM-6212)."""
        p = self._port(port, "digital")
        return self.reply(_GIO, p.port, p.bank).value

    def analog_input(self, port: int | str) -> int:
        """GIO <port>, <analog input bank> (bank 1 on the TMCM-6212): 0..65535."""
        p = self._port(port, "analog")
        return self.reply(_GIO, p.port, p.bank).value

    def output(self, port: int | str) -> int:
        """GIO <port>, <output bank>: the state of a digital output (bank 2)."""
        p = self._port(port, "output")
        return self.reply(_GIO, p.port, p.bank).value

    def set_output(self, port: int | str, value: int) -> None:
        """SIO <port>, <output bank>, <value> (bank 2)."""
        p = self._port(port, "output")
        value = int(value) if isinstance(value, bool) else check_int(value, "output value")
        self.request(_SIO, p.port, p.bank, value)

    def get_io(self, port: int, bank: int) -> int:
        """GIO <port>, <bank> with raw numbers."""
        return self.reply(_GIO, port, bank).value

    def set_io(self, port: int, bank: int, value: int) -> None:
        """SIO <port>, <bank>, <value> with raw numbers."""
        self.request(_SIO, port, bank, value)

    # --- events and motion ------------------------------------------------------------
    def request_position_reached_event(self, mask: int, *, every: bool = False) -> None:
        """Command 138: ask for a status-128 reply when the motors in `mask` reach their target,
        for the next MVP only or (`every`) for every MVP (manual 3.6.35)."""
        self.request(REQUEST_TARGET_REACHED_EVENT, 1 if every else 0, 0, mask)

    def wait_position_reached(self, mask: int, timeout: float | None = None) -> int:
        """Block until the status-128 replies for every motor in `mask` have arrived."""
        return self.client.wait_position_reached(mask, timeout, address=self.address)

    def stop_all(self) -> None:
        """MST on every axis."""
        for ax in self.axes:
            ax.stop()

    def sleep(self, seconds: float) -> None:
        """Let time pass on the module's clock (virtual time for sim:// modules)."""
        self.client.sleep(seconds)

    def _poll(self, done: Callable[[], bool], timeout: float | None, poll: float, what: str) -> None:
        transport = self.client.transport
        timeout = MOTION_TIMEOUT if timeout is None else check_timeout(timeout)
        _check_poll(poll)
        deadline = transport.monotonic() + timeout
        while not done():
            if transport.monotonic() >= deadline:
                raise TmclTimeout(f"{what} within {timeout:g} s")
            before = transport.monotonic()
            self.client.sleep(poll)
            if transport.monotonic() <= before:  # a clock that does not run
                raise TmclTimeout(f"{what}: time does not pass on this transport")

    # --- stored program and settings (manual 3.6.36) -----------------------------------
    def run_application(self, address: int | None = None) -> None:
        """Command 129: run the TMCL program from the current or a given address."""
        self.request(RUN_APPLICATION, 0 if address is None else 1, 0, address or 0)

    def stop_application(self) -> None:
        self.request(STOP_APPLICATION)

    def step_application(self) -> None:
        self.request(STEP_APPLICATION)

    def reset_application(self) -> None:
        self.request(RESET_APPLICATION)

    def download_program(self, instructions: Iterable[Iterable[int]], start: int = 0) -> int:
        """Store (command, type, motor, value) instructions in the TMCL memory from `start`:
        command 132, the instructions (each answered with status 101), command 133 (manual 3.6.36).
        Returns the number stored. Download mode is left even when an instruction is refused."""
        self.request(ENTER_DOWNLOAD_MODE, 0, 0, start)
        count = 0
        try:
            for instruction in instructions:
                try:
                    command, type, motor, value = instruction
                except (TypeError, ValueError):
                    raise TmclValueError(f"instruction {count} is not (command, type, motor, value): "
                                         f"{instruction!r}") from None
                self.request(command, type, motor, value)
                count += 1
        finally:
            self.request(EXIT_DOWNLOAD_MODE)
        return count

    def read_program_memory(self, address: int) -> tuple[int, int, int, int]:
        """Command 134: the (command, type, motor, value) stored at `address` (manual 3.6.36)."""
        r = self.client.read_memory(address, address=self.address)
        return r.command, r.type, r.motor, r.value

    def application_status(self, type: int = 0) -> int:
        """Command 135 (type 0: mode, wait flag, memory pointer ...)."""
        return self.reply(GET_APPLICATION_STATUS, type).value

    def restore_factory_settings(self) -> None:
        """Command 137 with value 1234; the module sends no reply (manual 3.6.36)."""
        self.request(RESTORE_FACTORY_SETTINGS, 0, 0, FACTORY_RESET_KEY)

    def close(self) -> None:
        """Close the transport (and with it every Module sharing the client)."""
        self.client.close()

    def __enter__(self) -> Module:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
