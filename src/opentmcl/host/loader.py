"""Download, verify and control TMCL programs over any client connection, as TMCL-IDE does
(TMCM-6212 manual 3.3, 3.6.36 Table 13; PD86-1180 manual 4.6.39).

    loader = Loader(opentmcl.connect("sim://TMCM-6212"))
    loader.download(program)        # 132 <start>, each instruction (status 101), 133, verify by 134
    loader.run()                    # 129 type 1 from the start address
    loader.status()                 # 135 types 1-3 (and the flags of an in-process virtual module)

`program` is a `lang.assembler.Program`, a list of (command, type, motor, value) tuples or
the bytes of a TMCL-IDE binary file.

Command 134 answers in a special format: the host address, then the stored instruction's
command, type, motor/bank and value in place of module address, status, command and value,
then a checksum (on CAN the seven bytes without host address and checksum). The manuals only
say "special reply format"; this layout is the one our virtual modules use
(docs/assumptions.md).
"""
from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

from ..lang.binfile import BinFileError, Instruction, decode
from ..protocol.frame import Reply, to_int32
from ..protocol.opcodes import (
    ENTER_DOWNLOAD_MODE,
    EXIT_DOWNLOAD_MODE,
    GET_APPLICATION_STATUS,
    RESET_APPLICATION,
    RUN_APPLICATION,
    STEP_APPLICATION,
    STOP_APPLICATION,
    Op,
)
from .client import Client, check_address
from .errors import TmclError, TmclStatusError, TmclTypeError, check_int, check_timeout

if TYPE_CHECKING:
    from .module import Module

_GGP = int(Op.GGP)  # a plain int, which `Client.request` keeps ready to send
MODES = {0: "stop", 1: "run", 2: "step", 3: "reset"}  # GP128 / 135 (TMCM-6212 manual 5.1)
Progress = Callable[[int, int], None]
"""A progress callback: (instructions done, instructions in all)."""

@runtime_checkable
class HasInstructions(Protocol):
    """A program object such as `lang.assembler.Program`: anything with an `instructions` list."""

    @property
    def instructions(self) -> Sequence[Iterable[int]]: ...


ProgramSource = HasInstructions | bytes | bytearray | memoryview | Iterable[Iterable[int]]
"""What `instructions_of` takes: a Program, a TMCL-IDE binary image or (command, type, motor,
value) tuples."""


class LoaderError(TmclError):
    """The program could not be loaded (too long, refused, or read back differently)."""


class VerifyError(LoaderError):
    """Read-back (134) differs from what was downloaded; `mismatches` = [(address, expected, got)]."""

    def __init__(self, mismatches: list[tuple[int, Instruction, Instruction]]):
        self.mismatches = mismatches
        addr, want, got = mismatches[0]
        more = f" (and {len(mismatches) - 1} more)" if len(mismatches) > 1 else ""
        super().__init__(f"verify failed at address {addr}: downloaded {tuple(want)}, read back "
                         f"{tuple(got)}{more}")


@dataclass(frozen=True)
class AppStatus:
    """Command 135: mode (0 stop, 1 run, 2 step, 3 reset), wait flag, program counter, A, X and
    the flags (None when the module does not report them)."""

    mode: int
    waiting: bool
    pc: int
    accumulator: int
    x_register: int
    flags: int | None = None

    @property
    def mode_name(self) -> str:
        return MODES.get(self.mode, str(self.mode))


def instructions_of(program: ProgramSource) -> list[Instruction]:
    """The instructions of a Program, a binary image or a sequence of 4-tuples."""
    if isinstance(program, (bytes, bytearray, memoryview)):
        try:
            return decode(bytes(program))
        except BinFileError as exc:
            raise LoaderError(f"not a TMCL binary image: {exc}") from None
    source = program.instructions if isinstance(program, HasInstructions) else program
    try:
        items = list(source)
    except TypeError:
        raise LoaderError(f"not a program (a Program, a binary image or 4-tuples): {program!r}") from None
    return [_instruction(ins) for ins in items]


def _instruction(ins: Iterable[int]) -> Instruction:
    """One (command, type, motor, value) of ints as an Instruction; LoaderError otherwise."""
    try:
        fields = [x for x in ins] if not isinstance(ins, (str, bytes)) else None
    except TypeError:
        fields = None
    if fields is None or len(fields) != 4 or any(isinstance(x, bool) or not isinstance(x, int) for x in fields):
        raise LoaderError(f"not an instruction (command, type, motor, value as ints): {ins!r}")
    command, type_, motor, value = fields
    return Instruction(command, type_, motor, value)


class Loader:
    """Program loader and application control for the module behind a `Client` or `Module`."""

    def __init__(self, target: Client | Module, address: int | None = None, *,
                 timeout: float | None = None) -> None:
        client = getattr(target, "client", target)
        if not isinstance(client, Client):
            raise TmclTypeError(f"Loader needs a Client or Module, got {type(target).__name__}")
        self.client = client
        self.address = check_address(address) if address is not None else getattr(target, "address", client.address)
        self.timeout = client.timeout if timeout is None else check_timeout(timeout)

    def request(self, command: int, type: int = 0, motor: int = 0, value: int = 0) -> Reply:
        """One request with a reply in the format of manual 3.2 (`Client.reply`): commands 134,
        136 type 0 and 137 are a TmclValueError (use `read_one` for 134)."""
        return self.client.reply(command, type, motor, value, address=self.address, timeout=self.timeout)

    # --- download / read back ---------------------------------------------------------------
    def download(self, program: ProgramSource, *, start: int = 0, verify: bool = True,
                 progress: Progress | None = None, verify_progress: Progress | None = None) -> list[Instruction]:
        """132 <start>, every instruction (answered 101), 133; then, if `verify`, read each back
        with 134 and compare. Returns the instructions written. `progress(done, total)` is called
        after each instruction written, `verify_progress(done, total)` after each one read back
        (for a progress bar; the library draws nothing)."""
        code = instructions_of(program)
        self.request(ENTER_DOWNLOAD_MODE, 0, 0, start)
        try:
            for i, ins in enumerate(code):
                try:
                    self.request(ins.command, ins.type, ins.motor, ins.value)
                except TmclStatusError as exc:
                    raise LoaderError(f"instruction {i} at address {start + i} {tuple(ins)} refused: "
                                      f"status {exc.status} ({exc.message})") from None
                if progress is not None:
                    progress(i + 1, len(code))
        finally:
            self.request(EXIT_DOWNLOAD_MODE)
        if verify:
            self.verify(code, start=start, progress=verify_progress)
        return code

    def verify(self, program: ProgramSource, *, start: int = 0, progress: Progress | None = None) -> None:
        """Compare program memory from `start` with `program` (134); VerifyError on a difference."""
        code = instructions_of(program)
        got = self.read(start, len(code), progress=progress)
        bad = [(start + i, want, have) for i, (want, have) in enumerate(zip(code, got, strict=True))
               if tuple(want) != tuple(have)]
        if bad:
            raise VerifyError(bad)

    def read(self, start: int, count: int, *, progress: Progress | None = None) -> list[Instruction]:
        """`count` instructions of program memory from `start` (command 134); `progress(done, count)`
        after each."""
        check_int(start, "start")
        check_int(count, "count")
        out = []
        for i in range(count):
            out.append(self.read_one(start + i))
            if progress is not None:
                progress(i + 1, count)
        return out

    def read_one(self, address: int) -> Instruction:
        """One program memory location (command 134, special reply)."""
        reply = self.client.read_memory(to_int32(check_int(address, "address")), address=self.address,
                                        timeout=self.timeout)
        return Instruction(reply.command, reply.type, reply.motor, reply.value)

    # --- application control (129-131, 135) ----------------------------------------------------
    def run(self, address: int | None = None) -> None:
        """129: type 0 from the current address, type 1 from `address`."""
        if address is None:
            self.request(RUN_APPLICATION, 0)
        else:
            self.request(RUN_APPLICATION, 1, 0, address)

    def stop(self) -> None:
        self.request(STOP_APPLICATION)

    def step(self) -> None:
        self.request(STEP_APPLICATION)

    def reset(self) -> None:
        self.request(RESET_APPLICATION)

    def status(self) -> AppStatus:
        """135 type 1 (mode, wait flag, PC), 2 (A), 3 (X); the flags where they can be read."""
        word = self.request(GET_APPLICATION_STATUS, 1).value & 0xFFFFFFFF
        a = self.request(GET_APPLICATION_STATUS, 2).value
        x = self.request(GET_APPLICATION_STATUS, 3).value
        return AppStatus(word >> 24, bool(word >> 16 & 0xFF), word & 0xFFFF, a, x, self.flags())

    def flags(self) -> int | None:
        """The program flags (ZE EQ GT LT and the error flags, layout of firmware/flags.py). No
        TMCL command reads them (135 lists types 0-3 only), so they are known only for a virtual
        module in this process (sim://, the dashboard of `serve --web`); None otherwise."""
        vm = self.client.transport.local_module(self.address)
        flags = getattr(vm, "flags", None)
        return flags if isinstance(flags, int) else None

    def variable(self, number: int) -> int:
        """User variable `number` (GGP <number>, 2)."""
        return self.request(_GGP, number, 2).value

    def wait_stopped(self, timeout: float, poll: float = 0.01) -> AppStatus:
        """Poll 135 until the program is no longer running (STOP reached) or `timeout` passes."""
        timeout = check_timeout(timeout)
        poll = check_timeout(poll, "poll interval")
        waited = 0.0
        while True:
            st = self.status()
            if st.mode != 1 or waited >= timeout:
                return st
            self.client.sleep(poll)
            waited += poll


def download(target: Client | Module, program: ProgramSource, *, start: int = 0, verify: bool = True) -> list[Instruction]:
    """Shortcut: `Loader(target).download(program, start=start, verify=verify)`."""
    return Loader(target).download(program, start=start, verify=verify)


__all__ = ["AppStatus", "Loader", "LoaderError", "VerifyError", "download", "instructions_of"]
