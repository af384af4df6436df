"""The presets as ready case JSON: the paper's cases (`fig3` … `fig9`), a rock drill and a pile,
one `<name>.json` file per preset in the presets folder.

The folder is `$PERCUSSIM_PRESETS` if set, else this package's own (the presets ship with it). A preset name is
only ever looked up among the files found there, never turned into a path, so a name such as
"../x" cannot reach a file outside the folder.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

from ..case import Case, load_case

PRESETS_ENV = "PERCUSSIM_PRESETS"
_NAME = re.compile(r"[a-z0-9_]+")


def presets_dir() -> Path:
    """The folder the presets are read from (read at every call, so the variable can change)."""
    folder = os.environ.get(PRESETS_ENV)
    return Path(folder) if folder else Path(__file__).resolve().parent


def _preset_files() -> dict[str, Path]:
    """Preset name -> file, for every `*.json` in the folder whose stem is a valid name."""
    return {
        path.stem: path
        for path in sorted(presets_dir().glob("*.json"))
        if _NAME.fullmatch(path.stem) and path.is_file()
    }


def preset_names() -> list[str]:
    """The names of the available presets, sorted."""
    return list(_preset_files())


def _preset_file(name: str) -> Path:
    """The file of preset `name`; `KeyError` naming the known presets if there is none."""
    files = _preset_files()
    # Only names matching _NAME are listed, so this also refuses "../x", "fig3.json", "FIG3".
    if name not in files:
        known = ", ".join(files) or "none"
        raise KeyError(f"unknown preset {name!r} (a name is lowercase letters, digits and '_'); known presets: {known}")
    return files[name]


def preset_json(name: str) -> dict:
    """Preset `name` as the case JSON stored in its file."""
    return json.loads(_preset_file(name).read_text())


def load_preset(name: str) -> Case:
    """Preset `name` as a validated case; `CaseError` if its file is not a valid case."""
    return load_case(_preset_file(name))
