"""Errors a user can act on: bad input (exit status 2) and failed solves (exit status 3)."""


class InputError(ValueError):
    """Bad scene, mesh or option: the message names the key and the problem in one line."""

    exit_status = 2


class SolveError(RuntimeError):
    """A solve that did not reach an answer (no convergence, inverted elements, NaN)."""

    exit_status = 3
