"""Keep FFCx's just-in-time compilation quiet: setuptools logs every compile at INFO on the root logger."""
import logging


def quiet_jit(verbose: bool = False) -> None:
    """Hide INFO-level compile logs unless verbose."""
    logging.disable(logging.NOTSET if verbose else logging.INFO)
