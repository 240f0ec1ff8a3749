"""Errors a user can act on: bad input (exit status 2) and failed solves (exit status 3)."""

MAX_MESSAGE = 300


def one_line(message: str, limit: int = MAX_MESSAGE) -> str:
    """The message on one line (control characters escaped) and at most `limit` characters."""
    text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(message))
    return text if len(text) <= limit else text[: limit - 3] + "..."


class InputError(ValueError):
    """Bad scene, mesh or option: the message names the key and the problem in one line
    (kept under MAX_MESSAGE characters, whatever value it quotes)."""

    exit_status = 2

    def __init__(self, message: str = ""):
        super().__init__(one_line(message))


class SolveError(RuntimeError):
    """A solve that did not reach an answer (no convergence, inverted elements, NaN)."""

    exit_status = 3
