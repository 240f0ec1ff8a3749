"""Modal and sound input: bad keys give one line and exit 2; an eigensolve that cannot converge exits 3."""
import pytest

from fem_forms import cli
from helpers import MODAL_E as E, modal_beam as beam, to_toml


def test_unconverged_eigensolve_is_exit_3(tmp_path, capsys):
    d = beam(count=6, solver={"petsc": {"eps_max_it": 1, "eps_tol": 1e-30}})
    (tmp_path / "scene.toml").write_text(to_toml(d))
    status = cli.main(["run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 3
    assert len(err) == 1 and "modes converged" in err[0], err


@pytest.mark.parametrize("change, key", [
    ({"modal": {"count": 0}}, "modal.count"),
    ({"modal": {"count": 3, "mass": "diagonal"}}, "modal.mass"),
    ({"modal": {"prestress": "yes"}}, "modal.prestress"),
    ({"modal": {"modes": 3}}, "modal.modes"),
    ({"material": {"model": "neo-hookean", "E": E, "nu": 0.0}}, "material.rho"),
    ({"sound": {"duration": 1.0}}, "sound.strike"),
    ({"sound": {"strike": {"point": [2.0, 0.0, 0.0], "direction": [0, 0, 1]}}}, "sound.strike.point"),
    ({"sound": {"strike": {"point": [0.5, 0.0, 0.0], "direction": [0, 0, 0]}}}, "sound.strike.direction"),
    ({"sound": {"strike": {"point": [0.5, 0.0, 0.0], "direction": [0, 0, 1]}, "sample_rate": 44.1}},
     "sound.sample_rate"),
    ({"sound": {"strike": {"point": [0.5, 0.0, 0.0], "direction": [0, 0, 1]},
                "damping": {"alpha": -1.0}}}, "sound.damping.alpha"),
])
def test_bad_modal_and_sound_input_is_one_line_exit_2(tmp_path, capsys, change, key):
    d = beam(count=2, cells=(4, 1, 1))
    d.update(change)
    (tmp_path / "scene.toml").write_text(to_toml(d))
    status = cli.main(["run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2
    assert len(err) == 1 and key in err[0], err
    assert not (tmp_path / "out" / "results.json").exists()
