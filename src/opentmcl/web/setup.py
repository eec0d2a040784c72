"""What the set-up wizards and the tuning tools read and write (docs/dashboard.md "Set-up wizards"):
a few named values at once, and a set of SAP/SGP that is applied whole or not at all.

`apply` first checks every write against the profile, reads the value each one replaces (GAP/GGP,
TMCM-6212 manual 3.6.6/3.6.8), then sends the SAP/SGP (3.6.5/3.6.7) in order. When the module
refuses one or the link fails, the ones already sent are written back to the values they replaced,
last first, so a wizard never leaves its settings half-applied. With `store`, each written value is
then stored with STAP/STGP (3.6.9; PD86-1180 4.6.7) where the module has the command: the TMCM-6212
has no STAP (its axis parameters are volatile, 3.6.5), so its axis values are reported as not stored.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..host import TmclError
from ..modules.profile import ModuleProfile
from ..protocol.opcodes import Op, format_instruction
from .service import READ_COMMANDS, Dashboard, DashboardError

MAX_ITEMS = 64   # values one request may read or write
_SAP, _SGP = int(Op.SAP), int(Op.SGP)  # plain ints for the requests


@dataclass(frozen=True)
class Item:
    kind: str    # "axis", "global" or "io"
    index: int   # axis, bank (global) or bank (io)
    number: int  # parameter number or port


def _item(x: object) -> Item:
    """One {kind, index, number} of the page, its types checked."""
    kind, index, number = (x.get(k) for k in ("kind", "index", "number")) if isinstance(x, dict) else (None,) * 3
    if kind not in ("axis", "global", "io") or not isinstance(index, int) or not isinstance(number, int) \
            or isinstance(index, bool) or isinstance(number, bool):
        raise DashboardError(f"a value is {{kind: axis|global|io, index, number}}, not {str(x)[:80]}")
    return Item(str(kind), index, number)


def _allowed(d: Dashboard, it: Item, writing: bool) -> bool:
    """Whether the profile lets `it` be read (GAP/GGP/GIO) or written (SAP/SGP)."""
    p = d.profile
    if it.kind == "axis":
        d.check_axis(it.index)
        q = p.axis_parameters.get(it.number)
        return q is not None and (q.writable if writing else q.readable)
    if it.kind == "global":
        g = p.global_parameters.get((it.index, it.number))
        return g is not None and (g.writable if writing else g.readable)
    io = p.io.get((it.index, it.number))
    return not writing and io is not None and "R" in io.access


def items(d: Dashboard, raw: object, *, writing: bool = False) -> list[Item]:
    """[{kind, index, number}, ...] checked against the profile (readable; writable when `writing`)."""
    if not isinstance(raw, list) or not raw or len(raw) > MAX_ITEMS:
        raise DashboardError(f"give 1..{MAX_ITEMS} values as [{{kind, index, number}}, ...]")
    out = []
    for x in raw:
        it = _item(x)
        if not _allowed(d, it, writing):
            raise DashboardError(f"{it.kind} parameter {it.number} ({'axis' if it.kind == 'axis' else 'bank'} "
                                 f"{it.index}) cannot be {'written' if writing else 'read'} on {d.profile.name}")
        out.append(it)
    return out


def _read_request(it: Item) -> tuple[int, int, int, int]:
    return (READ_COMMANDS[it.kind], it.number, it.index, 0)


def read(d: Dashboard, raw: object) -> list[dict[str, object]]:
    """The values of the items (None where the module refused or the link failed)."""
    wanted = items(d, raw)
    values = d.read_many([_read_request(it) for it in wanted])
    return [{"kind": it.kind, "index": it.index, "number": it.number, "value": v}
            for it, v in zip(wanted, values, strict=True)]


def _write_command(it: Item) -> int:
    """SAP for an axis parameter, SGP for a global one (TMCM-6212 manual 3.6.5, 3.6.7)."""
    return _SAP if it.kind == "axis" else _SGP


def _store_command(it: Item) -> Op:
    """STAP for an axis parameter, STGP for a global one (PD86-1180 manual 4.6.7, TMCM-6212 3.6.9)."""
    return Op.STAP if it.kind == "axis" else Op.STGP


def _text(command: int, it: Item, value: int = 0) -> str:
    """The instruction as the manual writes it ("SAP 6, 0, 127", "STAP 6, 0")."""
    return format_instruction(command, it.number, it.index, value) or f"{command}, {it.number}, {it.index}, {value}"


def _writes(d: Dashboard, raw: object) -> list[tuple[Item, int]]:
    if not isinstance(raw, list):
        raise DashboardError("writes must be a list of {kind, index, number, value}")
    wanted = items(d, raw, writing=True)
    out = []
    for it, x in zip(wanted, raw, strict=True):
        value = x.get("value")
        if isinstance(value, bool) or not isinstance(value, int):
            raise DashboardError(f"the value of {it.kind} parameter {it.number} must be an integer")
        p = d.profile.axis_parameters[it.number] if it.kind == "axis" else d.profile.global_parameters[(it.index, it.number)]
        allowed = value in p.values if p.values else p.min <= value <= p.max and value not in p.excluded
        if not allowed:
            raise DashboardError(f"{p.title} takes {p.min}..{p.max}, not {value} (nothing written)")
        out.append((it, value))
    return out


def apply(d: Dashboard, raw: object, store: bool = False) -> dict[str, object]:
    """SAP/SGP of every write, all or none (see the module docstring); {"sent": [instructions],
    "stored": [...], "not_stored": [why], "old": [{kind, index, number, value}]}."""
    writes = _writes(d, raw)
    old = d.read_many([_read_request(it) for it, _ in writes])
    if any(v is None for v in old):
        bad = next(it for (it, _), v in zip(writes, old, strict=True) if v is None)
        raise DashboardError(f"cannot read {bad.kind} parameter {bad.number} before writing it: nothing written")
    done: list[tuple[Item, int]] = []
    sent: list[str] = []
    try:
        for (it, value), before in zip(writes, old, strict=True):
            d.act(lambda it=it, value=value: d.module.request(_write_command(it), it.number, it.index, value))
            done.append((it, int(before or 0)))
            sent.append(_text(_write_command(it), it, value))
    except DashboardError as exc:
        undone = _undo(d, done)
        raise DashboardError(f"{exc}: nothing kept ({undone})") from None
    stored: list[str] = []
    not_stored: list[str] = []
    if store:
        kept: list[Item] = []
        try:
            _store(d, [it for it, _ in writes], stored, not_stored, kept)
        except DashboardError as exc:  # e.g. an EEPROM locked (status 5): the old values come back
            undone = _undo(d, done, restore_stored=kept)
            raise DashboardError(f"{exc}: nothing kept ({undone})") from None
    return {"sent": sent, "stored": stored, "not_stored": not_stored,
            "old": [{"kind": it.kind, "index": it.index, "number": it.number, "value": v}
                    for (it, _), v in zip(writes, old, strict=True)]}


def _undo(d: Dashboard, done: list[tuple[Item, int]], restore_stored: list[Item] | None = None) -> str:
    """Write back the values `done` replaced, last first (and store them again for the items of
    `restore_stored`, whose new value was already stored); what was restored, in words."""
    failed = []
    for it, before in reversed(done):
        try:
            d.module.request(_write_command(it), it.number, it.index, before)
            if restore_stored and it in restore_stored:
                d.module.request(_store_command(it), it.number, it.index, 0)
        except TmclError as exc:
            failed.append(f"{it.kind} parameter {it.number}: {exc}")
    if failed:
        return "could not restore " + "; ".join(failed)
    return f"{len(done)} value(s) written back" if done else "none was written"


def _store(d: Dashboard, written: list[Item], stored: list[str], not_stored: list[str], kept: list[Item]) -> None:
    """STAP/STGP of each written item the module can store; `stored` and `kept` grow as they go."""
    for it in written:
        command = _store_command(it)
        p = d.profile.axis_parameters[it.number] if it.kind == "axis" else d.profile.global_parameters[(it.index, it.number)]
        if command not in d.profile.opcodes:
            not_stored.append(f"{it.kind} parameter {it.number}: {d.profile.name} has no "
                              f"{command.name}")
            continue
        if not p.storable:
            not_stored.append(f"{it.kind} parameter {it.number}: not storable on {d.profile.name}")
            continue
        d.act(lambda it=it, command=command: d.module.request(command, it.number, it.index, 0))
        stored.append(_text(command, it))
        kept.append(it)


def reference_modes(profile: ModuleProfile) -> list[dict[str, object]]:
    """Each value AP193 takes, with the manual's words (the profile's `reference_modes`, mode 1
    first) and its additions: +64 "the right switch instead of the left one" (modes 1..4), +128
    the home switch (REFL) inverted; on a module that has the +64 modes, 129..132 are modes 5..8
    with the home switch inverted (TMCM-6212 manual 6.1.5-6.1.8, docs/world.md)."""
    p = profile.axis_parameters.get(193)
    texts = list(profile.extra.get("reference_modes", []))
    if p is None:
        return []
    out = []
    for mode in p.values or range(p.min, p.max + 1):
        base = mode & 63
        if mode & 128 and 1 <= base <= 4 and 64 + base in p.values:
            base += 4
        words = texts[base - 1] if 0 < base <= len(texts) else f"mode {base}"
        if mode & 64:
            words += "; the right switch instead of the left one (+64)"
        if mode & 128:
            words += "; the home switch inverted (+128)"
        out.append({"mode": mode, "text": words})
    return out
