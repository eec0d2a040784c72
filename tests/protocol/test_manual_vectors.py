"""Every binary example and reply example printed in the three manuals, as test vectors.

Each vector is transcribed from the manual: the mnemonic of the example and the bytes of its
"Binary Form of ..." table (TMCM-6212) or its "Value (hex)" row (PD86-1180, eight bytes without
checksum). Where a printed table contradicts itself, the test pins the contradiction (see
ERRATA below and docs/assumptions.md) instead of hiding it.
"""
from __future__ import annotations

import pytest

from opentmcl.protocol import can
from opentmcl.protocol.frame import Reply, Request, checksum
from opentmcl.protocol.opcodes import by_mnemonic, by_number, format_instruction, parse_instruction


def hexbytes(text: str) -> bytes:
    return bytes(int(t.lstrip("$"), 16) for t in text.split())


# TMCM-6212 manual, chapter 3.6: (section, mnemonic of the example, labels, the nine printed bytes).
# Label values are the ones the example assumes ("assuming Label at address 10", ...).
TMCM6212 = [
    ("3.6.1 ROR", "ROR 0, 51200", {}, "01 01 00 00 00 00 C8 00 CA"),
    ("3.6.2 ROL", "ROL 0, 51200", {}, "01 02 00 00 00 00 C8 00 CB"),
    ("3.6.3 MST", "MST 0", {}, "01 03 00 00 00 00 00 00 04"),
    ("3.6.4 MVP", "MVP REL, 0, -10000", {}, "01 04 01 00 FF FF D8 F0 CC"),
    ("3.6.4 MVP", "MVP COORD, 0, 8", {}, "01 04 02 00 00 00 00 08 0F"),
    ("3.6.5 SAP", "SAP 4, 0, 51200", {}, "01 05 04 00 00 00 C8 00 D2"),
    ("3.6.6 GAP", "GAP 1, 0", {}, "01 06 01 00 00 00 00 00 08"),
    ("3.6.7 SGP", "SGP 66, 0, 3", {}, "01 09 42 00 00 00 00 03 4F"),
    ("3.6.8 GGP", "GGP 66, 0", {}, "01 0A 42 00 00 00 00 00 4D"),
    ("3.6.9 STGP", "STGP 42, 2", {}, "01 0B 2A 02 00 00 00 00 38"),
    ("3.6.10 RSGP", "RSGP 42, 2", {}, "01 0C 2A 02 00 00 00 00 39"),
    ("3.6.11 RFS", "RFS START, 0", {}, "01 0D 00 00 00 00 00 00 0E"),
    ("3.6.11 RFS", "RFS START", {}, "01 0D 00 00 00 00 00 00 0E"),  # the table's own caption
    ("3.6.12 SIO", "SIO 3, 2, 1", {}, "01 0E 03 02 00 00 00 01 15"),
    ("3.6.13 GIO", "GIO 0, 1", {}, "01 0F 00 01 00 00 00 00 11"),
    ("3.6.14 CALC", "CALC MUL, -5000", {}, "01 13 02 00 FF FF EC 78 78"),
    ("3.6.15 COMP", "COMP 1000", {}, "01 14 00 00 00 00 03 E8 00"),
    ("3.6.16 JC", "JC GE, Label", {"Label": 10}, "01 15 05 00 00 00 00 0A 25"),
    ("3.6.17 JA", "JA Loop", {"Loop": 10}, "01 16 00 00 00 00 00 0A 21"),
    ("3.6.18 CSUB", "CSUB SubW", {"SubW": 100}, "01 17 00 00 00 00 00 64 7C"),
    ("3.6.19 RSUB", "RSUB", {}, "01 18 00 00 00 00 00 00 19"),
    ("3.6.20 WAIT", "WAIT POS, 0, 0", {}, "01 1B 01 00 00 00 00 00 1D"),
    ("3.6.21 STOP", "STOP", {}, "01 1C 00 00 00 00 00 00 1D"),
    ("3.6.22 SCO", "SCO 1, 0, 1000", {}, "01 1E 01 00 00 00 03 E8 0B"),
    ("3.6.23 GCO", "GCO 1, 0", {}, "01 1F 01 00 00 00 00 00 21"),
    ("3.6.25 ACO", "ACO 1, 0", {}, "01 27 01 00 00 00 00 00 29"),
    ("3.6.26 CALCX", "CALCX MUL", {}, "01 21 02 00 00 00 00 00 24"),
    ("3.6.27 AAP", "AAP 0, 0", {}, "01 22 00 00 00 00 00 00 23"),
    ("3.6.28 AGP", "AGP 42, 2", {}, "01 23 2A 02 00 00 00 00 50"),
    ("3.6.29 CLE", "CLE ETO", {}, "01 24 01 00 00 00 00 00 26"),
    ("3.6.30 EI", "EI 255", {}, "01 19 FF 00 00 00 00 00 19"),
    ("3.6.31 DI", "DI 255", {}, "01 1A FF 00 00 00 00 00 1A"),
]
IDS = [f"{sec}: {mn}" for sec, mn, _, _ in TMCM6212]


@pytest.mark.parametrize(("section", "mnemonic", "labels", "printed"), TMCM6212, ids=IDS)
def test_6212_binary_form_encodes_from_mnemonic(section, mnemonic, labels, printed):
    """TMCM-6212 3.6.x "Binary Form of <mnemonic>": assembling the example's mnemonic for module
    address 1 (the "Target address 01h" row) gives exactly the printed nine bytes."""
    cmd, typ, motor, value = parse_instruction(mnemonic, labels)
    assert Request(1, cmd, typ, motor, value).encode() == hexbytes(printed)


@pytest.mark.parametrize(("section", "mnemonic", "labels", "printed"), TMCM6212, ids=IDS)
def test_6212_binary_form_decodes_to_mnemonic(section, mnemonic, labels, printed):
    """TMCM-6212 3.6.x: the printed bytes decode (checksum verified) to the example's command, and
    the canonical text of the decoded fields reads back to the same fields."""
    req = Request.decode(hexbytes(printed))
    assert req.address == 1
    assert by_number(req.command).mnemonic == mnemonic.split()[0]
    inverse = {v: k for k, v in labels.items()}
    text = format_instruction(req.command, req.type, req.motor, req.value, labels=inverse)
    assert parse_instruction(text, labels) == (req.command, req.type, req.motor, req.value)


@pytest.mark.parametrize(("section", "mnemonic", "labels", "printed"), TMCM6212, ids=IDS)
def test_6212_binary_form_checksum(section, mnemonic, labels, printed):
    """TMCM-6212 3.1.1: the checksum is the 8-bit sum of the other eight bytes."""
    raw = hexbytes(printed)
    assert checksum(raw[:8]) == raw[8]


@pytest.mark.parametrize(("section", "mnemonic", "labels", "printed"), TMCM6212, ids=IDS)
def test_6212_mnemonic_operands_match_opcode_table(section, mnemonic, labels, printed):
    """TMCM-6212 3.4.1 / 3.6.x "Mnemonic:" lines: the example's operand count is an accepted form of
    its command, and the instruction number in the table is the command's number."""
    head, _, rest = mnemonic.partition(" ")
    count = len([p for p in rest.split(",") if p.strip()])
    cmd = by_mnemonic(head)
    assert cmd.form_for(count) is not None
    assert cmd.number == hexbytes(printed)[1]


# --- the printed tables that contradict themselves (TMCM-6212) --------------------------------

def test_6212_mvp_abs_90000_value_byte_typo():
    """TMCM-6212 3.6.4 "Binary Form of MVP ABS, 0, 90000" prints Value (Byte 2) = 10h and checksum
    F5h. 90000 = 0x00015F90, and F5h is the checksum of the bytes with 01h: the 10h is a typo."""
    printed = hexbytes("01 04 00 00 00 10 5F 90 F5")
    ours = Request(1, *parse_instruction("MVP ABS, 0, 90000")).encode()
    assert ours[8] == printed[8] == 0xF5
    assert ours[:8] == printed[:5] + bytes([0x01]) + printed[6:8]
    assert checksum(printed[:8]) != printed[8]


def test_6212_vect_and_reti_type_byte_typo():
    """TMCM-6212 3.6.32 "Binary form of VECT (assuming label is at 50)" for `VECT 0, Timer0Irq` and
    3.6.33 "Binary Form of RETI" print Type = FFh, but their checksums 58h and 27h are those of
    type 0, which is what the mnemonics say."""
    vect = Request(1, *parse_instruction("VECT 0, Timer0Irq", {"Timer0Irq": 50})).encode()
    reti = Request(1, *parse_instruction("RETI")).encode()
    assert vect == hexbytes("01 25 00 00 00 00 00 32 58")
    assert reti == hexbytes("01 26 00 00 00 00 00 00 27")


def test_6212_cco_example_bytes_are_cco_1():
    """TMCM-6212 3.6.24 "Binary Form of CCO 3, 0" prints Type 01h with a matching checksum 22h, so
    the printed bytes are CCO 1, 0; the mnemonic CCO 3, 0 gives type 03h as in PD86-1180 4.6.28."""
    printed = hexbytes("01 20 01 00 00 00 00 00 22")
    req = Request.decode(printed)
    assert format_instruction(req.command, req.type, req.motor, req.value) == "CCO 1, 0"
    assert Request(1, *parse_instruction("CCO 3, 0")).encode()[:8] == hexbytes("01 20 03 00 00 00 00 00")


def test_6212_command_138_example():
    """TMCM-6212 3.6.35 "Binary Form for this example": 138 type 1 with value 05h, checksum 91h
    (the prose says motors #2 and #3; the printed bit mask 5 selects motors 0 and 2)."""
    from opentmcl.protocol.replies import motors_in_mask
    req = Request.decode(hexbytes("01 8A 01 00 00 00 00 05 91"))
    assert (req.command, req.type, req.motor, req.value) == (138, 1, 0, 5)
    assert by_number(138).mnemonic is None and not by_number(138).program
    assert motors_in_mask(req.value) == [0, 2]


# --- reply examples --------------------------------------------------------------------------

def test_6212_gio_reply_example():
    """TMCM-6212 3.6.13 "Reply (Status=no error, Value=302)": 02 01 64 0F 00 00 01 2E A5."""
    raw = hexbytes("02 01 64 0F 00 00 01 2E A5")
    assert Reply.decode(raw) == Reply(2, 1, 100, 15, 302)
    assert Reply(2, 1, 100, 15, 302).encode() == raw


def test_6212_calc_reply_example():
    """TMCM-6212 3.6.14 "Reply (Status=no error, value=-5000": 02 01 64 13 FF FF EC 78 DC."""
    raw = hexbytes("02 01 64 13 FF FF EC 78 DC")
    assert Reply.decode(raw) == Reply(2, 1, 100, 19, -5000)
    assert Reply(2, 1, 100, 19, -5000).encode() == raw


def test_6212_command_138_replies():
    """TMCM-6212 3.6.35 "Reply in Direct Mode" (status 64h, command 8Ah, motor bit mask) and
    "Additional Reply after Motor has reached Target Position" (status 80h). The manual's table
    lists the target address before the host address; the reply format of 3.2 (reply address
    first) is used, as in PD86-1180 4.6.37 ($02 $01 ...)."""
    from opentmcl.protocol.replies import is_target_reached_event, target_reached_event
    immediate = Reply(2, 1, 100, 138, 5).encode()
    event = target_reached_event(2, 1, 5).encode()
    assert immediate[:8] == hexbytes("02 01 64 8A 00 00 00 05")
    assert event[:8] == hexbytes("02 01 80 8A 00 00 00 05")
    assert event[8] == checksum(event[:8])
    assert is_target_reached_event(Reply.decode(event))
    assert not is_target_reached_event(Reply.decode(immediate))


# PD86-1180 manual 4.6: (section, mnemonic, labels, the eight printed bytes: address + 7, no checksum)
PD86_1180 = [
    ("4.6.1 ROR", "ROR 0, 350", {}, "$01 $01 $00 $00 $00 $00 $01 $5e"),
    ("4.6.2 ROL", "ROL 0, 1200", {}, "$01 $02 $00 $00 $00 $00 $04 $b0"),
    ("4.6.3 MST", "MST 0", {}, "$01 $03 $00 $00 $00 $00 $00 $00"),
    # printed mnemonic "MVP ABS, 0, 9000", prose "position 90000"; the bytes are 90000
    ("4.6.4 MVP", "MVP ABS, 0, 90000", {}, "$01 $04 $00 $00 $00 $01 $5f $90"),
    ("4.6.4 MVP", "MVP REL, 0, -1000", {}, "$01 $04 $01 $00 $ff $ff $fc $18"),
    ("4.6.4 MVP", "MVP COORD, 0, 8", {}, "$01 $04 $02 $00 $00 $00 $00 $08"),
    ("4.6.5 SAP", "SAP 6, 0, 200", {}, "$01 $05 $06 $00 $00 $00 $00 $c8"),
    # printed mnemonic "GAP 0, 1" (parameter 1 of motor 0 in the bytes: actual position)
    ("4.6.6 GAP", "GAP 1, 0", {}, "$01 $06 $01 $00 $00 $00 $00 $00"),
    ("4.6.7 STAP", "STAP 4, 0", {}, "$01 $07 $04 $00 $00 $00 $00 $00"),
    ("4.6.8 RSAP", "RSAP 6, 0", {}, "$01 $08 $06 $00 $00 $00 $00 $00"),
    ("4.6.9 SGP", "SGP 66, 0, 3", {}, "$01 $09 $42 $00 $00 $00 $00 $03"),
    ("4.6.10 GGP", "GGP 66, 0", {}, "$01 $0a $42 $00 $00 $00 $00 $00"),
    ("4.6.11 STGP", "STGP 42, 2", {}, "$01 $0b $2a $02 $00 $00 $00 $00"),
    ("4.6.12 RSGP", "RSGP 42, 2", {}, "$01 $0c $2a $02 $00 $00 $00 $00"),
    ("4.6.13 RFS", "RFS START, 0", {}, "$01 $0d $00 $00 $00 $00 $00 $00"),
    ("4.6.14 SIO", "SIO 7, 2, 1", {}, "$01 $0e $07 $02 $00 $00 $00 $01"),
    ("4.6.15 GIO", "GIO 0, 1", {}, "$01 $0f $00 $01 $00 $00 $00 $00"),
    ("4.6.16 CALC", "CALC MUL, -5000", {}, "$01 $13 $02 $00 $FF $FF $EC $78"),
    ("4.6.17 COMP", "COMP 1000", {}, "$01 $14 $00 $00 $00 $00 $03 $e8"),
    ("4.6.18 JC", "JC GE, Label", {"Label": 10}, "$01 $15 $05 $00 $00 $00 $00 $0a"),
    ("4.6.19 JA", "JA Loop", {"Loop": 20}, "$01 $16 $00 $00 $00 $00 $00 $14"),
    ("4.6.20 CSUB", "CSUB SubW", {"SubW": 100}, "$01 $17 $00 $00 $00 $00 $00 $64"),
    ("4.6.21 RSUB", "RSUB", {}, "$01 $18 $00 $00 $00 $00 $00 $00"),
    ("4.6.22 WAIT", "WAIT POS, 0, 0", {}, "$01 $1b $01 $00 $00 $00 $00 $00"),
    ("4.6.23 STOP", "STOP", {}, "$01 $1c $00 $00 $00 $00 $00 $00"),
    ("4.6.24 SCO", "SCO 1, 0, 1000", {}, "$01 $1e $01 $00 $00 $00 $03 $e8"),
    ("4.6.25 GCO", "GCO 1, 0", {}, "$01 $1f $01 $00 $00 $00 $00 $00"),
    ("4.6.26 CCO", "CCO 3, 0", {}, "$01 $20 $03 $00 $00 $00 $00 $00"),
    ("4.6.27 ACO", "ACO 1, 0", {}, "$01 $27 $01 $00 $00 $00 $00 $00"),
    ("4.6.28 CALCX", "CALCX MUL", {}, "$01 $21 $02 $00 $00 $00 $00 $00"),
    ("4.6.29 AAP", "AAP 0, 0", {}, "$01 $22 $00 $00 $00 $00 $00 $00"),
    ("4.6.30 AGP", "AGP 3, 2", {}, "$01 $23 $03 $02 $00 $00 $00 $00"),
    ("4.6.31 CLE", "CLE ETO", {}, "$01 $24 $01 $00 $00 $00 $00 $00"),
    ("4.6.32 VECT", "VECT 3, 500", {}, "$01 $25 $03 $00 $00 $00 $01 $F4"),
    ("4.6.33 EI", "EI 255", {}, "$01 $19 $FF $00 $00 $00 $00 $00"),
    ("4.6.33 EI", "EI 3", {}, "$01 $19 $03 $00 $00 $00 $00 $00"),
    ("4.6.34 DI", "DI 255", {}, "$01 $1A $FF $00 $00 $00 $00 $00"),
    ("4.6.34 DI", "DI 3", {}, "$01 $1A $03 $00 $00 $00 $00 $00"),
]


@pytest.mark.parametrize(("section", "mnemonic", "labels", "printed"), PD86_1180,
                         ids=[f"{s}: {m}" for s, m, _, _ in PD86_1180])
def test_1180_binary_examples(section, mnemonic, labels, printed):
    """PD86-1180 4.6.x "Binary:" rows (byte index 0..7: target address, instruction, type,
    motor/bank, operand bytes 3..0; no checksum column): the mnemonic encodes to those bytes, and
    bytes 1..7 are the CAN payload (4.1: "When using CAN bus, just leave out the first byte
    (module address) and the last byte (checksum)")."""
    raw = hexbytes(printed)
    cmd, typ, motor, value = parse_instruction(mnemonic, labels)
    frame = Request(1, cmd, typ, motor, value).encode()
    assert frame[:8] == raw
    assert can.encode_request(cmd, typ, motor, value) == raw[1:]
    assert can.decode_request(raw[1:]) == can.CanRequest(cmd, typ, motor, value)


def test_1180_reti_example_value_field():
    """PD86-1180 4.6.35 "Binary format of RETI" prints $01 $26 $00 $00 $00 $00 $01 $00: the value
    field (don't care for RETI) is 256; it decodes to RETI with a non-zero don't-care value."""
    raw = hexbytes("$01 $26 $00 $00 $00 $00 $01 $00")
    req = Request.decode(raw + bytes([checksum(raw)]))
    assert by_number(req.command).mnemonic == "RETI" and req.value == 256
    assert Request(1, *parse_instruction("RETI")).encode()[:8] == raw[:6] + b"\x00\x00"


@pytest.mark.parametrize(("section", "printed", "fields"), [
    ("4.6.6 GAP reply: status=no error, position=711", "$02 $01 $64 $06 $00 $00 $02 $c7", (2, 1, 100, 6, 711)),
    ("4.6.10 GGP reply", "$02 $01 $64 $0a $00 $00 $00 $01", (2, 1, 100, 10, 1)),
    ("4.6.15 GIO reply", "$02 $01 $64 $0f $00 $00 $01 $fa", (2, 1, 100, 15, 506)),
    # 4.6.25 prints instruction $0a in the GCO reply (GCO is 31 = $1f): transcribed as printed
    ("4.6.25 GCO reply", "$02 $01 $64 $0a $00 $00 $00 $00", (2, 1, 100, 10, 0)),
])
def test_1180_reply_examples(section, printed, fields):
    """PD86-1180 4.6.x "Reply:" rows (host address, target address, status, instruction, operand
    bytes 3..0; the checksum column is not printed): decode with the computed checksum, and the
    CAN reply payload is the same without the reply address (4.2)."""
    raw = hexbytes(printed)
    assert Reply.decode(raw + bytes([checksum(raw)])) == Reply(*fields)
    assert can.encode_reply(*fields[1:]) == raw[1:]
    assert can.decode_reply(raw[1:]) == can.CanReply(*fields[1:])


def test_1180_command_138_replies():
    """PD86-1180 4.6.37: immediate reply $02 $01 100 138 ... mask, additional reply $02 $01 128 138."""
    from opentmcl.protocol.replies import target_reached_event
    assert Reply(2, 1, 100, 138, 1).encode()[:4] == bytes([2, 1, 100, 138])
    assert target_reached_event(2, 1, 1).encode()[:4] == bytes([2, 1, 128, 138])


# --- printed reply frames, answered by the virtual modules ----------------------------------------
# (module, section, request fields, setup, printed reply). The 6212 prints nine bytes with the
# checksum; the 1180 eight bytes without it. Setup puts the module in the state the example
# assumes (the value it reads).

def _drive_adc(value):
    return lambda vm: vm.world.set_input(1, 0, value)


def _position(value):
    return lambda vm: vm.request(5, 1, 0, value)


REPLY_VECTORS = [
    ("TMCM-6212", "3.6.13 GIO 0, 1 (Value=302)", (15, 0, 1, 0), _drive_adc(302), "02 01 64 0F 00 00 01 2E A5"),
    ("TMCM-6212", "3.6.14 CALC MUL, -5000 (value=-5000)", (19, 2, 0, -5000), None, "02 01 64 13 FF FF EC 78 DC"),
    ("TMCM-6212", "3.6.35 138 type 1, mask 5 (reply in direct mode)", (138, 1, 0, 5), None, "02 01 64 8A 00 00 00 05"),
    ("PD86-1180", "4.6.6 GAP 1, 0 (position=711)", (6, 1, 0, 0), _position(711), "$02 $01 $64 $06 $00 $00 $02 $c7"),
    ("PD86-1180", "4.6.10 GGP 66, 0 (Value=1)", (10, 66, 0, 0), None, "$02 $01 $64 $0a $00 $00 $00 $01"),
    ("PD86-1180", "4.6.15 GIO 0, 1 (value 506)", (15, 0, 1, 0), _drive_adc(506), "$02 $01 $64 $0f $00 $00 $01 $fa"),
    # printed with instruction $0a; GCO is 31 = $1f (see test_1180_reply_examples)
    ("PD86-1180", "4.6.25 GCO 1, 0", (31, 1, 0, 0), None, "$02 $01 $64 $1f $00 $00 $00 $00"),
    ("PD86-1180", "4.6.37 138 type 0, motor bit mask 1", (138, 0, 0, 1), None, "$02 $01 $64 $8a $00 $00 $00 $01"),
    ("PD86-1180", "4.6.16 CALC MUL, -5000 (TMCM-6212 3.6.14 reply)", (19, 2, 0, -5000), None,
     "$02 $01 $64 $13 $FF $FF $EC $78"),
    ("PD28-1021", "CALC MUL, -5000 (TMCM-6212 3.6.14 reply, docs/assumptions.md)", (19, 2, 0, -5000), None,
     "02 01 64 13 FF FF EC 78 DC"),
]


def test_printed_reply_frames_are_what_the_modules_answer():
    """TMCM-6212 3.6.14 "Reply in Direct Mode: 100 - OK, the operand" and its printed reply
    (02 01 64 13 FF FF EC 78 DC), and every other printed reply frame of the manuals (6212 3.6.13,
    3.6.35; PD86-1180 4.6.6, 4.6.10, 4.6.15, 4.6.25, 4.6.37): the request sent to a module at address 1
    with host address 2 (the defaults) gets exactly the printed bytes."""
    from opentmcl import VirtualModule
    got, want = {}, {}
    for module, section, (cmd, typ, motor, value), setup, printed in REPLY_VECTORS:
        vm = VirtualModule(module, address=1)
        if setup is not None:
            setup(vm)
        raw = vm.handle(Request(1, cmd, typ, motor, value).encode())
        printed_bytes = hexbytes(printed)
        got[section] = raw[:len(printed_bytes)]
        want[section] = printed_bytes
        assert raw[8] == checksum(raw[:8])
    assert got == want


@pytest.mark.parametrize(("module", "mask", "printed"), [
    ("TMCM-6212", 5, "02 01 80 8A 00 00 00 05"),          # 3.6.35 (status 80h), motors 0 and 2
    ("PD86-1180", 1, "$02 $01 $80 $8a $00 $00 $00 $01"),  # 4.6.37 "$02 $01 128 138 ... Motor bit mask"
])
def test_printed_additional_reply_after_the_target_is_reached(module, mask, printed):
    """TMCM-6212 3.6.35 / PD86-1180 4.6.37 "Additional reply ... after motor has reached target
    position": after 138 and an MVP of each motor in the mask, the module sends the printed frame
    once per motor with that motor's bit (docs/assumptions.md, Command 138)."""
    from opentmcl import VirtualModule
    vm = VirtualModule(module, address=1)
    assert vm.request(138, 0, 0, mask).status == 100
    motors = [m for m in range(6) if mask >> m & 1]
    for m in motors:
        vm.request(4, 0, m, 1000)
    vm.advance(5.0)
    events = vm.drain_events()
    assert [e[:4] for e in events] == [hexbytes(printed)[:4]] * len(motors)
    assert sorted(Reply.decode(e).value for e in events) == [1 << m for m in motors]
    assert sum(Reply.decode(e).value for e in events) == int.from_bytes(hexbytes(printed)[4:8], "big")
