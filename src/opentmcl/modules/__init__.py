"""Module profiles (data): parameter tables, I/O map, interrupt vectors, limits."""
from .profile import Interrupt, IOPort, ModuleProfile, Param, load_profile, module_names, parse_profile

__all__ = ["IOPort", "Interrupt", "ModuleProfile", "Param", "load_profile", "module_names", "parse_profile"]
