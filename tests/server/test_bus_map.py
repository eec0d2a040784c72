"""The bus address map (server/bus.py): a frame reaches the modules of its address byte only, and
the bus answers exactly as if every frame were offered to every module.

TMCM-6212 manual 3.1 (the address byte), 3.6.7 (SGP; example SGP 66, 0, 3), 5.1 (GP66 RS485
address, GP87 secondary address, GP255 reply suppression), 3.6.36 (137 restore factory settings);
PD28-1021 manual 3.4 (command 139 enters ASCII mode).
"""
from __future__ import annotations

from opentmcl import VirtualModule
from opentmcl.server.bus import USB, ModuleBus

from .helpers import SGP_66_3, reply, request


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


class Counted(VirtualModule):
    """A module that counts the frames handed to it and the advances of its time."""

    def __init__(self, *args, **kwargs):
        self.handled = 0
        self.advances = 0
        super().__init__(*args, **kwargs)

    def handle(self, frame, *, interface="serial"):
        self.handled += 1
        return super().handle(frame, interface=interface)

    def advance(self, seconds):
        self.advances += 1
        super().advance(seconds)


class Usb:
    interface = USB

    def deliver(self, vm, data):
        pass


def offered_to_all(twins, frame):
    """The reference: the frame offered to every module in binary mode (the bus before the map)."""
    out = []
    for vm in twins:
        if vm.ascii_mode:
            continue
        answer = vm.handle(frame)
        if answer:
            out.append(answer)
    return out


def test_only_the_addressed_module_reads_the_frame():
    """Eight modules at 1..8: GGP 66 to address 5 is handed to module 5 alone."""
    mods = [Counted("TMCM-6212", address=i) for i in range(1, 9)]
    bus = ModuleBus(mods, clock=Clock())
    assert [r for _, r in bus.request(request(5, 10, 66))] == [reply(2, 5, 100, 10, 5)]
    assert [m.handled for m in mods] == [0, 0, 0, 0, 1, 0, 0, 0]


def test_sgp_66_moves_the_module_in_the_map():
    """Manual 3.6.7 example SGP 66, 0, 3 to module 1: its reply still comes from address 1, then
    the module answers at 3 and no longer at 1."""
    mods = [VirtualModule("TMCM-6212", address=1), VirtualModule("TMCM-6212", address=2)]
    bus = ModuleBus(mods, clock=Clock())
    assert [r for _, r in bus.request(SGP_66_3)] == [reply(2, 1, 100, 9, 0)]
    assert bus.request(request(1, 10, 66)) == []
    assert [r for _, r in bus.request(request(3, 10, 66))] == [reply(2, 3, 100, 10, 3)]


def test_secondary_address_gp87_and_switching_it_off():
    mods = [VirtualModule("TMCM-6212", address=1), VirtualModule("TMCM-6212", address=2)]
    bus = ModuleBus(mods, clock=Clock())
    bus.request(request(2, 9, 87, 0, 9))                 # SGP 87, 0, 9: secondary address 9
    assert [vm for vm, _ in bus.request(request(9, 10, 66))] == [mods[1]]
    bus.request(request(9, 9, 87, 0, 0))                 # through 9, secondary off (0)
    assert bus.request(request(9, 10, 66)) == []
    assert [vm for vm, _ in bus.request(request(2, 10, 66))] == [mods[1]]


def test_two_modules_at_one_address_both_answer_in_module_order():
    mods = [VirtualModule("TMCM-6212", address=1), VirtualModule("PD86-1180", address=2)]
    bus = ModuleBus(mods, clock=Clock())
    bus.request(request(2, 9, 66, 0, 1))  # module 2 moves to 1 as well
    assert [vm for vm, _ in bus.request(request(1, 10, 66))] == mods


def test_restore_factory_settings_137_brings_the_given_address_back():
    """137 (no reply, manual 3.6.36) resets GP66 to the address the module was started at."""
    vm = VirtualModule("TMCM-6212", address=2)
    bus = ModuleBus([vm], clock=Clock())
    bus.request(request(2, 9, 66, 0, 5))
    assert bus.request(request(5, 137, 0, 0, 1234)) == []
    assert [r for _, r in bus.request(request(2, 10, 66))] == [reply(2, 2, 100, 10, 2)]
    assert bus.request(request(5, 10, 66)) == []


def test_a_module_in_ascii_mode_gets_no_binary_frames():
    """PD28-1021 manual 3.4.1: command 139 enters ASCII mode; binary frames to it go unanswered."""
    mods = [VirtualModule("PD28-1021", address=1), VirtualModule("TMCM-6212", address=2)]
    bus = ModuleBus(mods, clock=Clock())
    assert [r for _, r in bus.request(request(1, 139))] == [reply(2, 1, 100, 139, 0)]
    assert bus.request(request(1, 10, 66)) == []
    assert [vm for vm, _ in bus.request(request(2, 10, 66))] == [mods[1]]


def test_usb_ignores_the_address_byte():
    """A link that stands for USB: any address byte reaches the one module, whose reply carries
    its own address."""
    vm = VirtualModule("TMCM-6212", address=1)
    bus = ModuleBus([vm], clock=Clock())
    assert [r for _, r in bus.request(request(7, 10, 66), Usb())] == [reply(2, 1, 100, 10, 1)]
    assert bus.request(request(7, 10, 66)) == []


def test_an_address_changed_outside_the_bus_is_found():
    """`assign_address` behind the bus's back: a frame to the new address finds the module (a map
    miss looks again), the old address is silent (the module filters it itself)."""
    vm = VirtualModule("TMCM-6212", address=1)
    bus = ModuleBus([vm], clock=Clock())
    assert bus.request(request(1, 10, 66))
    vm.assign_address(4)
    assert bus.request(request(1, 10, 66)) == []
    assert [r for _, r in bus.request(request(4, 10, 66))] == [reply(2, 4, 100, 10, 4)]
    other = VirtualModule("TMCM-6212", address=4)
    bus2 = ModuleBus([vm, other], clock=Clock())
    assert len(bus2.request(request(4, 10, 66))) == 2
    other.assign_address(6)                    # leaves 4: the stale entry finds it silent
    assert [m for m, _ in bus2.request(request(4, 10, 66))] == [vm]


def test_a_program_that_sets_its_address_while_time_passes():
    """A TMCL program's SGP 66, 0, 7 (run with command 129) takes effect as time passes; the map
    follows it."""
    vm = VirtualModule("TMCM-6212", address=1)
    for frame in ((132, 0, 0, 0), (9, 66, 0, 7), (28, 0, 0, 0), (133, 0, 0, 0)):  # SGP, STOP
        vm.handle(request(1, *frame))
    clock = Clock()
    bus = ModuleBus([vm], clock=clock)
    assert bus.request(request(1, 10, 66))
    bus.request(request(1, 129))   # run from address 0
    clock.t += 0.05
    assert [r for _, r in bus.request(request(7, 10, 66))] == [reply(2, 7, 100, 10, 7)]
    assert bus.request(request(1, 10, 66)) == []


def test_differential_against_offering_every_frame_to_every_module():
    """A script of address changes, suppression and reads on three modules: the bus's replies equal
    those of twin modules that each see every frame."""
    def three():
        return [VirtualModule("TMCM-6212", address=1), VirtualModule("PD86-1180", address=2),
                VirtualModule("TMCM-6212", address=3)]
    mods, twins = three(), three()
    bus = ModuleBus(mods, clock=Clock())
    script = [request(a, 10, 66) for a in range(0, 6)] + [
        request(1, 9, 87, 0, 2), request(2, 10, 66), request(2, 9, 66, 0, 3), request(3, 6, 1, 0),
        request(3, 9, 255, 0, 1), request(3, 5, 4, 0, 100), request(3, 6, 4, 0), request(2, 12, 66, 0),
        request(1, 9, 87, 0, 0), request(2, 10, 66), request(3, 137, 0, 0, 1234), request(1, 10, 87),
        request(2, 10, 66), request(3, 10, 66), request(3, 9, 66, 0, 0), request(0, 10, 66),
    ] + [request(a, 10, 66) for a in range(0, 6)]
    for frame in script:
        assert [r for _, r in bus.request(frame)] == offered_to_all(twins, frame), frame.hex(" ")


def test_no_time_sync_when_no_time_has_passed():
    """Requests at one instant do not advance the modules; the first one after time moved does."""
    vm = Counted("TMCM-6212", address=1)
    clock = Clock()
    bus = ModuleBus([vm], clock=clock, min_step=0.0)
    for _ in range(5):
        bus.request(request(1, 6, 1, 0))
    assert vm.advances == 0
    clock.t += 0.01
    bus.request(request(1, 6, 1, 0))
    bus.request(request(1, 6, 1, 0))
    assert vm.advances == 1


def test_serial_frames_fast_path_uses_the_map():
    """`serial_frames` (the SerialStream fast path) reaches the addressed module only."""
    mods = [Counted("TMCM-6212", address=i) for i in (1, 2, 3)]
    bus = ModuleBus(mods, clock=Clock())
    with bus.lock:
        out = bus.serial_frames(request(3, 10, 66))
    assert [(vm, data) for vm, data, _ in out] == [(mods[2], reply(2, 3, 100, 10, 3))]
    assert [m.handled for m in mods] == [0, 0, 1]


def test_the_map_is_kept_while_time_passes_without_a_program():
    """Only a running TMCL program can change GP66/GP87 while time passes (TMCM-6212 manual 3.6.7
    SGP, 3.6.36 command 129): with no program running, the bus does not rebuild its map after an
    advance; with one running, it does (so the program's SGP 66 is seen, as the test above shows)."""
    clock = Clock()
    mods = [VirtualModule("TMCM-6212", address=i) for i in (1, 2)]
    bus = ModuleBus(mods, clock=clock, min_step=0.0)
    builds = []
    build = bus._build_map
    bus._build_map = lambda: builds.append(1) or build()
    bus.request(request(1, 6, 1, 0))
    for _ in range(3):
        clock.t += 0.01
        assert [r for _, r in bus.request(request(2, 6, 1, 0))] == [reply(2, 2, 100, 6, 0)]
    assert len(builds) == 1
    mods[1].handle(request(2, 132))                       # download: WAIT TICKS 1000, STOP
    mods[1].handle(request(2, 27, 0, 0, 1000))
    mods[1].handle(request(2, 28))
    mods[1].handle(request(2, 133))
    bus.request(request(2, 129))                          # run: not a map-keeping command
    bus.request(request(1, 6, 1, 0))
    n = len(builds)
    clock.t += 0.01
    bus.request(request(1, 6, 1, 0))
    assert len(builds) == n + 1


def test_differential_with_time_and_a_program_moving_an_address():
    """Requests between advances while module 2's program toggles its GP66 between 2 and 5
    (SGP 66, 0, 5 / WAIT TICKS 1 (10 ms, manual 3.6.25) / SGP 66, 0, 2 / WAIT TICKS 1 / JA 0): the
    bus answers exactly as twin modules that each see every frame and the same time steps."""
    program = [(9, 66, 0, 5), (27, 0, 0, 1), (9, 66, 0, 2), (27, 0, 0, 1), (22, 0, 0, 0)]

    def pair():
        mods = [VirtualModule("TMCM-6212", address=1), VirtualModule("TMCM-6212", address=2)]
        mods[1].handle(request(2, 132))
        for ins in program:
            mods[1].handle(request(2, *ins))
        mods[1].handle(request(2, 133))
        mods[1].handle(request(2, 129))
        return mods
    mods, twins = pair(), pair()
    clock = Clock()
    bus = ModuleBus(mods, clock=clock, min_step=0.0)
    frames = [request(a, 6, 1, 0) for a in (1, 2, 5)] + [request(a, 10, 66) for a in (1, 2, 5)]
    seen = set()
    for step in range(40):
        clock.t += 0.003
        for vm in twins:
            vm.advance(0.003)
        for frame in frames:
            answers = [r for _, r in bus.request(frame)]
            assert answers == offered_to_all(twins, frame), (step, frame.hex(" "))
            seen.update(r[1] for r in answers)
    assert seen == {1, 2, 5}  # the program did move module 2 to 5 and back
