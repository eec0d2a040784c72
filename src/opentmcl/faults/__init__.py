"""Faults on demand (docs/faults.md): the failures real rigs have, described as data, decided
from a seed, applied where they belong and recorded when they fire.

    plan = load_plan("faults.toml")          # or parse_plan({...}), or a scenario's [[fault]] tables
    board = FaultBoard(plan)                 # one running set-up: seed, log, trigger by name
    link = board.link("tcp")                 # the link faults of one link: LinkFaults.request(...)

This package sits below the host library, the firmware and the servers, so all of them share one
description and one way to decide: the link faults are applied by the endpoints (server/) and the
in-process transport (host/transports/faulty.py), the module faults by the virtual module
(firmware/faults.py).
"""
from .board import FaultBoard, new_seed
from .link import Fate, LinkFaults, corrupt, cut, describe, survives
from .log import FaultLog, Fired
from .spec import (
    KINDS,
    LINK_KINDS,
    MODULE_KINDS,
    Fault,
    FaultError,
    FaultPlan,
    command_number,
    load_plan,
    parse_fault,
    parse_faults,
    parse_plan,
    parse_seed,
    seed_of,
)
from .trigger import Trigger, stream

__all__ = ["KINDS", "LINK_KINDS", "MODULE_KINDS", "Fate", "Fault", "FaultBoard", "FaultError", "FaultLog",
           "FaultPlan", "Fired", "LinkFaults", "Trigger", "command_number", "corrupt", "cut", "describe",
           "load_plan", "new_seed", "parse_fault", "parse_faults", "parse_plan", "parse_seed", "seed_of", "stream",
           "survives"]
