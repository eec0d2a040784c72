"""The served bus (issue 16): `ModuleBus` of 1, 2, 4 or 8 TMCM-6212 at addresses 1..N, as
`opentmcl serve --module TMCM-6212 --module TMCM-6212 ...` builds it (server/app.py `Server`),
with a virtual clock (`clock=`) advanced 10 ms per poll; each poll sends 6 GAPs to every module
(GAP 1 = actual position of axes 0-5, TMCM-6212 manual 3.6.6) through `bus.request(frame)`.
All six axes of every module move (MVP far away). Figure: virtual s per wall s; reference: the
same modules polled directly (`vm.advance` + `vm.handle` per module, no bus) in the same run.

    python bench/bench_bus.py [--quick]
"""
from __future__ import annotations

from bench_polling import CHUNK, check_moving, start_moves
from figures import Figure, best_of, print_figures, timed
from opentmcl import VirtualModule
from opentmcl.protocol.frame import Request
from opentmcl.server.bus import ModuleBus

DT = 0.01


def modules(n: int) -> list[VirtualModule]:
    out = []
    for address in range(1, n + 1):
        vm = VirtualModule("TMCM-6212", address=address)
        start_moves(vm.request, 6)
        out.append(vm)
    return out


def frames_for(address: int) -> list[bytes]:
    return [Request(address, 6, 1, a, 0).encode() for a in range(6)]


def served(n: int, budget: float) -> float:
    vms = modules(n)
    now = [0.0]
    bus = ModuleBus(vms, clock=lambda: now[0])
    frames = [f for address in range(1, n + 1) for f in frames_for(address)]
    request = bus.request

    def step() -> float:
        for _ in range(CHUNK):
            now[0] += DT
            for f in frames:
                if len(request(f)) != 1:
                    raise RuntimeError("a bus request was not answered by exactly one module")
        return CHUNK * DT
    out = timed(step, budget)
    for vm in vms:
        check_moving(lambda a, vm=vm: vm.request(6, 8, a).value, 6)  # type: ignore[union-attr]
    return out


def direct(n: int, budget: float) -> float:
    pairs = [(vm.advance, vm.handle, frames_for(vm.address)) for vm in modules(n)]

    def step() -> float:
        for _ in range(CHUNK):
            for advance, handle, frames in pairs:
                advance(DT)
                for f in frames:
                    handle(f)
        return CHUNK * DT
    return timed(step, budget)


def measure(quick: bool = False) -> list[Figure]:
    rounds, budget = (1, 0.04) if quick else (3, 0.4)
    out = []
    for n in (1, 2, 4, 8):
        bus, plain = best_of(rounds, [lambda n=n: served(n, budget), lambda n=n: direct(n, budget)])
        out.append(Figure(f"served bus of {n} TMCM-6212, 6 GAPs each per 10 ms, virtual s/wall s", bus, plain,
                          ">= 5x today" if n == 8 else "", "the same modules without the bus"))
    return out


def main() -> None:
    print_figures(measure, __doc__ or "")


if __name__ == "__main__":
    main()
