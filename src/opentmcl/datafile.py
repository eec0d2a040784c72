"""Data files a user writes: TOML, or YAML with the suffix .yaml/.yml (scenarios, fault plans).

    data = read_document("stage.toml", "scenario")     # the parsed table (a dict), or None if empty

Reading is bounded (limits.py: a regular file of at most TEXT_MAX bytes). Every failure is a
`DocumentError` (a ValueError) of one line naming the file: cannot be read, too large, not
valid TOML or YAML, nested too deeply, an integer of more than 4300 digits.
"""
from __future__ import annotations

import os
import tomllib
from pathlib import Path
from typing import Any

from .limits import TEXT_MAX, InputTooLarge, read_bytes


class DocumentError(ValueError):
    """A data file that cannot be read or parsed (one line, naming the file)."""


def read_document(source: str | os.PathLike[str], what: str) -> Any:
    """The parsed content of a TOML file (YAML for .yaml/.yml): what the parser answers, None for
    an empty YAML file. `what` names the file in messages ("scenario", "fault plan")."""
    path = Path(source)
    try:
        text = read_bytes(path, TEXT_MAX, f"{what} file")
    except InputTooLarge as exc:
        raise DocumentError(f"cannot read {what} {path}: {exc}") from None
    except OSError as exc:
        raise DocumentError(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    if path.suffix.lower() in (".yaml", ".yml"):
        import yaml  # type: ignore[import-untyped]  # imported here: most data files are TOML

        try:
            return yaml.safe_load(text)
        except (yaml.YAMLError, ValueError) as exc:   # PyYAML's message spans lines: one line here
            raise DocumentError(f"{path}: {' '.join(str(exc).split())}") from None
        except RecursionError:
            raise DocumentError(f"{path}: nested too deeply") from None
    try:
        return tomllib.loads(text.decode("utf-8"))
    except ValueError as exc:   # TOMLDecodeError, UnicodeDecodeError, an integer of over 4300 digits
        raise DocumentError(f"{path}: {exc}") from None
    except RecursionError:
        raise DocumentError(f"{path}: nested too deeply") from None
