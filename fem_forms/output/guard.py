"""Optional output after a solve that converged: a failure there (a stress recovery, a field file, a
picture) must not lose the solution. Each optional part runs through `attempt`, which turns an error
into one warning line in results.json and lets the caller write what is already known (the displacement,
the numbers of the solve)."""
from __future__ import annotations

from typing import Callable, TypeVar

from fem_forms.errors import InputError

T = TypeVar("T")


def attempt(warnings: list, what: str, action: Callable[[], T], default: T | None = None) -> T | None:
    """action(), or `default` with a warning "<what> failed after the converged solve (...): left out"
    appended to `warnings`. Bad input (InputError) and interrupts still propagate."""
    try:
        return action()
    except InputError:
        raise
    except Exception as e:                       # noqa: BLE001 (any failure of an optional output)
        why = (str(e).strip().splitlines() or [type(e).__name__])[0]
        warnings.append(f"{what} failed after the converged solve ({type(e).__name__}: {why}): left out")
        return default
