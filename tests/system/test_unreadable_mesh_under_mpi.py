"""A mesh file that rank 0 cannot read fails on every rank with one line (exit 2), never a hang of the
ranks waiting for rank 0's broadcast."""
import pytest

from helpers import mpirun, toml_dumps


@pytest.mark.mpi
def test_a_corrupt_mesh_file_is_one_line_on_two_ranks(tmp_path):
    bad = tmp_path / "part.vtu"
    bad.write_text("<VTKFile>this is not a mesh")
    scene = tmp_path / "scene.toml"
    scene.write_text(toml_dumps({"mesh": {"generator": "file", "file": str(bad)},
                                 "material": {"model": "neo-hookean", "E": 1e6, "nu": 0.3, "rho": 1000.0},
                                 "fix": [{"where": {"axis": "x", "at": 0.0}}],
                                 "load": [{"type": "gravity"}]}))
    p = mpirun(["-m", "fem_forms", "run", str(scene), "--out", str(tmp_path / "out"), "-q"])
    lines = [line for line in p.stderr.splitlines() if line.startswith("fem-forms: error:")]
    assert len(lines) == 1 and "mesh" in lines[0], p.stderr[-2000:]
    assert "Traceback" not in p.stderr
    assert not (tmp_path / "out" / "results.json").exists()
