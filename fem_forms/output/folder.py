"""The output folder a run writes into, checked before anything runs: nothing a run writes may land outside it.

Every file name written there comes from the package; what could still lead a write out is a symbolic link, one
that came with a shared folder (a zip holding the scene and an out/ folder whose results.json links to a dotfile).
A link inside the folder that points out of it is refused, and the default folder out/<stem>/ is not reached
through a link either. A folder the user names with --out is theirs: it may itself be a link."""
from __future__ import annotations

import os
from pathlib import Path

from fem_forms.errors import InputError

HINT = "fem-forms writes nothing through links: remove it or choose another --out"


def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def check_output_folder(out: Path, default: bool) -> None:
    """Refuse `out` (one line, InputError) when a write into it could follow a link out of it; `default`: the
    folder was not named by the user (out/<stem>/), so neither it nor out/ may be a link."""
    if default:
        if out.name in ("", ".", ".."):
            raise InputError(f"output folder {str(out)!r}: the scene file's name gives no folder; choose --out")
        for part in (out.parent, out):
            if part.is_symlink():
                raise InputError(f"output folder {str(part)!r}: a symbolic link (to {os.readlink(part)!r}); {HINT}")
    if not out.is_dir():
        return
    root = out.resolve()
    for folder, dirs, files in os.walk(out, followlinks=False):
        for name in dirs + files:
            entry = Path(folder) / name
            if not entry.is_symlink():
                continue
            try:
                target = entry.resolve(strict=False)
            except (OSError, RuntimeError):              # a loop of links
                target = None
            if target is None or not _inside(target, root):
                raise InputError(f"output folder {str(out)!r}: {str(entry)!r} is a symbolic link out of it (to "
                                 f"{os.readlink(entry)!r}); {HINT}")
