"""`opentmcl log show`: a capture file as a readable table with round-trip latencies.

    opentmcl log show FILE [--address N] [--command MNEMONIC]
"""
from __future__ import annotations

import argparse
import logging

from . import CliError


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("log", help="read capture files written by opentmcl proxy --log",
                              description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="log_command", metavar="ACTION", required=True)
    show = sub.add_parser("show", help="print a capture as a table")
    show.add_argument("file", metavar="FILE")
    show.add_argument("--address", "-a", type=int, metavar="N", help="only frames of module address N")
    show.add_argument("--command", "-c", dest="command_filter", metavar="MNEMONIC", help="only frames of this command, e.g. GAP or 138")
    show.set_defaults(func=run_show)


def _command_filter(text: str | None) -> int | None:
    from ..protocol.opcodes import UnknownCommand, by_mnemonic

    if text is None:
        return None
    if text.isdigit():
        return int(text)
    try:
        return by_mnemonic(text).number
    except UnknownCommand as exc:
        raise CliError(str(exc)) from None


def row(rec: dict) -> str:
    """One table row of a frame record."""
    from ..protocol.opcodes import format_instruction

    arrow = "->" if rec["dir"] == "host" else "<-"
    kind = rec["kind"]
    if kind == "request":
        text = format_instruction(rec["command"], rec["type"], rec["motor"], rec["value"]) or \
            f"command {rec['command']} {rec['type']}, {rec['motor']}, {rec['value']}"
        if not rec.get("checksum_ok", True):
            text += "  (wrong checksum)"
    elif kind in ("reply", "event"):
        text = f"{rec['status']} {rec.get('status_text', '')}  {rec.get('mnemonic', rec.get('command'))} = {rec['value']}"
    elif kind == "version":
        text = f"version {rec.get('version')!r}"
    elif kind == "memory":
        text = f"program memory {rec['raw']}"
    elif kind == "ascii":
        text = repr(rec.get("text", ""))
    else:
        text = f"garbage {rec['raw']}"
    address = rec.get("address", "")
    latency = f"{rec['latency'] * 1000:8.3f}" if isinstance(rec.get("latency"), (int, float)) else " " * 8
    name = rec.get("parameter", "")
    return f"{rec['t']:12.6f}  {arrow} {address!s:>3}  {kind:<8} {latency}  {text}" + (f"  [{name}]" if name else "")


def run_show(args: argparse.Namespace) -> int:
    from ..capture import CaptureError, read_capture

    command = _command_filter(args.command_filter)
    try:
        cap = read_capture(args.file)
    except CaptureError as exc:
        raise CliError(str(exc)) from None
    for warning in cap.warnings:   # a torn last line (docs/capture.md)
        logging.getLogger("opentmcl.cli").warning("warning: %s", warning)
    head = cap.header
    print(f"# {head.get('tool', '?')} capture of {head.get('target', '?')} started {head.get('start', '?')}")
    link = cap.link
    if "link" in head:
        print(f"# link {link['interface']}, {link['baud'] or 'speed unknown'} baud, "
              f"{float(link['frame_time']) * 1000:.3f} ms per frame")
    from ..capture.snapshot import snapshot_of

    for address in sorted({r["address"] for r in cap.snapshots}):
        snap = snapshot_of(cap, address)
        if snap is not None:
            print(f"# snapshot of address {address} ({snap.module or '?'}) at {snap.t:.3f} s: {snap.count()} values"
                  + ("" if snap.complete else ", cut off"))
    for ident in cap.identities:
        print(f"# address {ident.get('address')}: firmware {ident.get('firmware_version')!r}"
              + (f" = {ident['module']}" if ident.get("module") else ""))
    print(f"{'time s':>12}  dir adr  kind     RTT ms    frame")
    for rec in cap.frames:
        if args.address is not None and rec.get("address") != args.address:
            continue
        if command is not None and rec.get("command") != command:
            continue
        print(row(rec))
    return 0
