"""Bad inverse-design settings: one line naming the key, exit status 2."""
import pytest

from helpers import beam_scene, inverse_beam, run_scene, with_


BAD = [
    (with_(inverse_beam(), "inverse.method", "magic"), "inverse.method = 'magic'"),
    (with_(inverse_beam(), "inverse.smoothness", 1.0), "inverse.smoothness: only for method = 'adjoint'"),
    (with_(inverse_beam(), "inverse.target", "missing.msh"), "inverse.target = 'missing.msh': file not found"),
    (with_(inverse_beam(method="adjoint"), "inverse.match_region", {"box": [[5, 5, 5], [6, 6, 6]]}),
     "inverse.match_region: contains no cell"),
    (with_(inverse_beam(method="adjoint"), "inverse.max_move", -1.0), "inverse.max_move = -1.0"),
    (with_(beam_scene(), "inverse", {"method": "direct"}), "inverse: only for analysis = 'inverse'"),
    (with_(inverse_beam(), "inverse.check", "quick"), "inverse.check = 'quick': must be one of 'equilibrium', 'path'"),
]


@pytest.mark.parametrize("scene, fragment", BAD, ids=[b[1][:30] for b in BAD])
def test_bad_inverse_settings(tmp_path, capsys, scene, fragment):
    code, _, err, out = run_scene(tmp_path, scene, capsys)
    assert code == 2 and fragment in err and len(err.strip().splitlines()) == 1, err
