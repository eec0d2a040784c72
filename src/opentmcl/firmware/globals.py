"""Global parameters: bank 0 (module configuration), bank 2 (user variables),
bank 3 (interrupt configuration) — TMCM-6212 manual 5, PD86-1180 manual 6.

Bank-0 parameters 64..127 are stored automatically by SGP (both manuals:
"An SGP command on such a parameter will always store it permanently"), as
are parameters with access letter A. GP73 locks the configuration EEPROM
(PD86-1180 manual 6.1: write 1234 to lock, 4321 to unlock; read 1/0); while
locked, anything that would write the EEPROM answers status 5.
"""
from __future__ import annotations

import random
from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING

from ..motion import CLOCK_HZ
from ..protocol.frame import to_int32
from .status import TmclStatus

if TYPE_CHECKING:
    from .vm import VirtualModule

USER_BANK = 2
LOCK_CODE, UNLOCK_CODE = 1234, 4321


class GlobalParameters:
    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm
        self.params = vm.profile.global_parameters
        self.ram: dict[tuple[int, int], int] = {}
        for key, p in self.params.items():
            stored = vm.eeprom.get_global(*key) if self.auto_stored(key) or p.storable else None
            self.ram[key] = p.default if stored is None else stored
        self.ram[(0, 255)] = 0  # "reset to 0 on startup"
        self.eeprom_locked = bool(vm.eeprom.get_global(0, 73) or 0)
        self._tick_offset = 0
        self._random = random.Random(0)

    def auto_stored(self, key: tuple[int, int]) -> bool:
        bank, number = key
        p = self.params.get(key)
        if p is None or number == 255:
            return False
        return p.auto_stored or (bank == 0 and 64 <= number < 128)

    def get_raw(self, bank: int, number: int) -> int:
        """RAM value without access checks (0 for parameters the module lacks)."""
        return self.ram.get((bank, number), 0)

    # --- SGP / GGP ----------------------------------------------------------------
    def get(self, bank: int, number: int) -> int:
        """GGP (TMCM-6212 3.6.8): the value now; TmclStatus(3) if it cannot be read."""
        return self.reader(bank, number)()

    def reader(self, bank: int, number: int) -> Callable[[], int]:
        """The read of global parameter `number` of `bank`: the one rule of GGP, which the request
        path and programs bind ahead. TmclStatus(3) if it cannot be read."""
        vm = self.vm
        if bank == USER_BANK:
            return partial(vm.user_vars.__getitem__, self._user_index(number))
        key = (bank, number)
        p = self.params.get(key)
        if p is None or not p.readable:
            raise TmclStatus(3)
        special = self._SPECIAL.get(key) if bank == 0 else None
        if special is not None:
            return partial(special, self)
        return partial(self.ram.__getitem__, key)

    def _locked(self) -> int:
        return int(self.eeprom_locked)

    def _status(self) -> int:
        return self.vm.application_status

    def _download(self) -> int:
        return int(self.vm.download_mode)

    def _pc(self) -> int:
        return self.vm.program_counter

    def _ticks(self) -> int:
        return to_int32(self.vm.scheduler.now * 1000 // CLOCK_HZ + self._tick_offset)

    def _next_random(self) -> int:
        return self._random.randrange(0, 2**31)

    _SPECIAL: dict[tuple[int, int], Callable[[GlobalParameters], int]] = {
        (0, 73): _locked, (0, 128): _status, (0, 129): _download, (0, 130): _pc, (0, 132): _ticks,
        (0, 133): _next_random}
    """GP73 lock, 128 application status, 129 download mode, 130 program counter, 132 tick timer,
    133 random number: values that do not live in RAM."""

    def set(self, bank: int, number: int, value: int) -> None:
        vm = self.vm
        if bank == USER_BANK:
            vm.user_vars[self._user_index(number)] = value
            return
        key = (bank, number)
        p = self.params.get(key)
        if p is None or not p.writable:
            raise TmclStatus(3)
        if key == (0, 73):
            self._set_lock(value)
            return
        if p.max > 0x7FFF_FFFF and value < 0:  # unsigned 32-bit ranges (bank-3 timer periods)
            value += 1 << 32
        if not p.accepts(value):
            raise TmclStatus(4)
        if key == (0, 132):
            self._tick_offset = value - vm.scheduler.now * 1000 // CLOCK_HZ
            return
        if key == (0, 133):
            self._random.seed(value)
            return
        if self.auto_stored(key):
            if self.eeprom_locked:
                raise TmclStatus(5)
            vm.eeprom.set_global(bank, number, value)
        if key == (0, 81):
            self._set_protection(self.ram[key], value)
        self.ram[key] = value

    def _set_lock(self, value: int) -> None:
        if value == LOCK_CODE:
            self.eeprom_locked = True
        elif value == UNLOCK_CODE:
            self.eeprom_locked = False
        else:
            raise TmclStatus(4)
        self.vm.eeprom.set_global(0, 73, int(self.eeprom_locked))

    def _set_protection(self, old: int, new: int) -> None:
        """GP81: switching off protection against disassembling erases the program."""
        if old in (1, 3) and new in (0, 2):
            self.vm.erase_program()

    # --- STGP / RSGP ---------------------------------------------------------------
    def store(self, bank: int, number: int) -> None:
        vm = self.vm
        if bank == USER_BANK:
            idx = self._user_index(number)
            if idx >= vm.profile.storable_user_variables:
                raise TmclStatus(3)
            self._check_unlocked()
            vm.eeprom.set_user(idx, vm.user_vars[idx])
            return
        key = (bank, number)
        p = self.params.get(key)
        if p is None or not (p.storable or self.auto_stored(key)):
            raise TmclStatus(3)
        self._check_unlocked()
        vm.eeprom.set_global(bank, number, self.ram[key])

    def restore(self, bank: int, number: int) -> None:
        vm = self.vm
        if bank == USER_BANK:
            idx = self._user_index(number)
            if idx >= vm.profile.storable_user_variables:
                raise TmclStatus(3)
            stored = vm.eeprom.get_user(idx)
            vm.user_vars[idx] = 0 if stored is None else stored
            return
        key = (bank, number)
        p = self.params.get(key)
        if p is None or not (p.storable or self.auto_stored(key)):
            raise TmclStatus(3)
        stored = vm.eeprom.get_global(bank, number)
        self.ram[key] = p.default if stored is None else stored

    def _check_unlocked(self) -> None:
        if self.eeprom_locked:
            raise TmclStatus(5)

    def _user_index(self, number: int) -> int:
        if not 0 <= number < len(self.vm.user_vars):
            raise TmclStatus(3)
        return number
