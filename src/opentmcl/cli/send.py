"""`opentmcl send "MVP ABS, 0, 1000" --to URL`: send direct-mode commands and print the replies.

An instruction is written as in TMCL source (TMCM-6212 manual 3.6: ``MVP ABS, 0, 1000``,
``GAP 1, 0``, ``SAP 4, 0, 51200``) or, for control commands that have no mnemonic (manual
3.6.36), as numbers ``COMMAND, TYPE, MOTOR, VALUE`` (e.g. ``136, 0, 0, 0``).

Each reply is one line with its status as the manual words it (TMCM-6212 manual 3.2.1, table 4):

  status 100 (Successfully executed, no error), value 51200
  version 6212V105                  (136 type 0: the special reply, which has no status)
  instruction MVP REL, 0, -10000    (134: the stored instruction)

--plain prints the value alone (51200, 6212V105, MVP REL, 0, -10000), for scripts; -v the whole
reply. A reply with an error status is an error (exit status 4, docs/cli.md).
"""
from __future__ import annotations

import argparse
import os
from typing import TYPE_CHECKING

from ..protocol.opcodes import GET_FIRMWARE_VERSION
from . import CliError

if TYPE_CHECKING:
    from ..host import Client, VersionReply
    from ..protocol.frame import Reply
    from ..protocol.replies import MemoryReply

ENV_URL = "OPENTMCL_URL"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("send", help="send TMCL direct-mode commands to a module and print the replies",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("instructions", nargs="+", metavar="INSTRUCTION",
                   help='e.g. "MVP ABS, 0, 1000", "GAP 1, 0" or "136, 0, 0, 0"')
    p.add_argument("--to", dest="url", default=os.environ.get(ENV_URL),
                   help=f"module URL: sim://TMCM-6212, tcp://HOST:PORT, serial:///dev/ttyUSB0?baud=9600, "
                        f"can://socketcan/can0?id=1 (default ${ENV_URL})")
    p.add_argument("--address", type=int, default=None,
                   help="module address (default 1, or the address a sim:// URL sets); "
                        "on CAN the URL's ?id=N chooses the module")
    p.add_argument("--host-address", type=int, default=2, help="reply (host) address (default 2)")
    p.add_argument("--timeout", type=float, default=5.0, help="seconds to wait for each reply (default 5)")
    p.add_argument("--plain", action="store_true",
                   help="print each reply's value alone (a number, the version string, the instruction): for scripts")
    p.add_argument("-v", "--verbose", action="count", default=0,
                   help="print the whole reply (addresses, status, command, value); also log at INFO "
                        "(-vv: DEBUG, every frame); --plain still prints the value alone")
    p.set_defaults(func=run)


def parse(text: str) -> tuple[int, int, int, int]:
    """(command, type, motor, value) of one instruction (`opentmcl.lang.direct`); CliError if unreadable."""
    from ..lang.direct import InstructionError, parse_direct

    try:
        return parse_direct(text)
    except InstructionError as exc:
        raise CliError(str(exc)) from None


def _show(reply: Reply | VersionReply | MemoryReply | None, verbose: bool, plain: bool) -> str:
    """One reply as the user reads it (the default), its value alone (`plain`) or whole (`verbose`)."""
    from ..host import VersionReply
    from ..protocol.replies import MemoryReply
    from ..protocol.status import message

    if reply is None:
        return "(no reply)"
    if isinstance(reply, VersionReply):
        if plain:
            return reply.text
        return f"host {reply.reply_address}: {reply.text}" if verbose else f"version {reply.text}"
    if isinstance(reply, MemoryReply):  # command 134: the stored instruction
        from ..protocol.opcodes import format_instruction

        fields = (reply.command, reply.type, reply.motor, reply.value)
        shown = format_instruction(*fields) or ", ".join(map(str, fields))
        return shown if plain else f"instruction {shown}"
    if plain:
        return str(reply.value)
    if not verbose:
        return f"status {reply.status} ({message(reply.status)}), value {reply.value}"
    return (f"host {reply.reply_address}, module {reply.module_address}, status {reply.status} "
            f"({message(reply.status)}), command {reply.command}, value {reply.value}")


def _name_the_module(client: Client, args: argparse.Namespace) -> None:
    """After an error status, the module type for the hint (cli/exits.py `status_hint`) when the
    command line does not name it: from the module's version string (command 136 type 0, TMCM-6212
    manual 3.6.36), as `connect` finds its profile. Nothing when it cannot be told."""
    from ..host import TmclError, VersionReply
    from ..host.module import profile_for_version
    from .exits import module_of

    if module_of(args) is not None:
        return
    try:
        reply = client.request(GET_FIRMWARE_VERSION, 0, 0, 0)
        if isinstance(reply, VersionReply):
            args.module = profile_for_version(reply.text).name
    except (TmclError, ValueError):
        pass


def run(args: argparse.Namespace) -> int:
    from ..host import TmclError, TmclStatusError, open_bus

    if not args.url:
        raise CliError(f"no module URL: give --to URL (or set ${ENV_URL})")
    if args.address is not None and args.url.strip().lower().startswith("can:"):
        # CAN frames carry no address byte (manual 3.1): the CAN ID in the URL picks the module.
        raise CliError("on CAN the module is chosen by its CAN ID in the URL (can://IFACE/CHANNEL?id=N), "
                       "not by --address")
    requests = [parse(text) for text in args.instructions]  # all parsed before anything is sent
    if not 0 < args.timeout < float("inf"):  # also NaN
        raise CliError(f"--timeout must be a positive number of seconds, got {args.timeout}")
    try:
        client = open_bus(args.url, address=args.address, timeout=args.timeout, host_address=args.host_address)
    except (TmclError, ValueError) as exc:
        raise CliError(str(exc)) from None
    try:
        for command, type_, motor, value in requests:
            try:
                reply = client.request(command, type_, motor, value)
            except (TmclError, ValueError, TypeError) as exc:
                if isinstance(exc, TmclStatusError):
                    _name_the_module(client, args)
                raise CliError(str(exc)) from None
            print(_show(reply, args.verbose, args.plain), flush=True)
    finally:
        client.close()
    return 0
