"""Reference search command state (RFS START/STOP/STATUS, TMCM-6212 manual 3.6.11).

RFS START sets the axis searching: it drives towards the switch the mode
searches first with the reference search speed (AP194) until the search
completes or RFS STOP ends it. The switch-driven state machines of every mode
belong to the axis-world model.
"""
from __future__ import annotations


class ReferenceSearch:
    def __init__(self, axis) -> None:
        self.axis = axis
        self.active = False

    def start(self) -> None:
        ax = self.axis
        mode = ax.ram.get(193, 1) & 0x3F
        speed = ax.ram.get(194, 0)
        direction = 1 if mode in (6, 7) else -1  # modes 6/7 search in positive direction first
        if mode in (2, 3):
            direction = 1  # "search right stop switch, then ..."
        self.active = True
        ax.engine.rotate(ax.to_engine(194, direction * speed))

    def stop(self) -> None:
        if self.active:
            self.active = False
            self.axis.engine.stop()

    def status(self) -> int:
        return int(self.active)
