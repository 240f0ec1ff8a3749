"""The mixed (Taylor-Hood) formulation is refused where it does not apply."""
import pytest

import fem_forms as ff
from helpers import incompressible_beam as beam


def test_mixed_needs_degree_2_and_static():
    with pytest.raises(ff.InputError, match="Taylor-Hood"):
        beam(0.49, "mixed", 1)
