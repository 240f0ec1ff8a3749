"""A PneuNet's stiff layer designed for a 120 degree curl (layout design, analysis = "design").

    python demos/pneunet_layout.py OUT_DIR

The PneuNet actuator of demos/scenes/pneunet.toml (a soft Mooney-Rivlin silicone, E 100 kPa, six chambers) is
inflated by injecting 36 ml of air (18 ml into its half: the model is the half y <= 0, rollers on the
plane of symmetry). All soft, it curls 95 degrees. The design may cast a ten times stiffer
silicone (neo-Hookean, E 1 MPa) anywhere in the 6 mm solid base under the chambers, at most half of it, and looks
for the least of it that turns the end face by 120 degrees (an angle target: the segment from the end's bottom
edge to its top edge, about y). Then, independently of the design's own solve, a plain static scene reads the
written layout.msh (the two materials by volume group) and inflates it by the same volume; the same static scene
all in the soft silicone gives the curl without the layer. Prints the design, both curls and the layout's volume;
writes placed.stl and body.stl (the insert and the body to cast: their halves, to mirror in the plane y = 0) and
layout.png.
"""
from pathlib import Path
import sys
import tomllib

import fem_forms as ff
from fem_forms.analyses import run_analysis

HERE = Path(__file__).parent
SCENE = HERE / "scenes" / "pneunet_layout.toml"
sys.path.insert(0, str(HERE / "geometry"))
import pneunet  # noqa: E402


def static_curl(data: dict, out: Path, mesh: Path, materials: list) -> float:
    """The tip angle (degrees) of a plain static run of the scene's actuator on `mesh` with `materials`."""
    scene = {k: v for k, v in data.items() if k != "design"}
    scene.update(analysis="static", mesh={"generator": "file", "file": str(mesh)}, material=materials,
                 output=dict(data["output"], fields=[]))
    r = run_analysis(ff.Scene.from_dict(scene, base_dir=SCENE.parent), out)
    u = {name: r["probes"][name]["displacement"] for name in ("tip_top", "tip_bottom")}
    return pneunet.tip_angle(u["tip_top"], u["tip_bottom"])


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    r = run_analysis(ff.Scene.from_file(SCENE), out / "design")
    d = r["design"]
    turned = d["angles"]["tip_bottom->tip_top"]
    print(f"{r['title']}: {d['layouts_tried']} layouts in {r['wall_time_s']:.0f} s, {r['dofs']} dofs")
    print(f"  hard silicone in {d['placed_fraction_cast']:.1%} of the base (bound {d['placed_fraction_bound']:.0%}):"
          f" {1e6 * d['placed_volume_m3']:.2f} cm^3, {d['gray_fraction']:.1%} of the base gray before casting")
    print(f"  the cast layout curls {turned['reached_deg']:.2f} deg (target {turned['target_deg']:g} deg)")
    data = tomllib.loads(SCENE.read_text())
    soft, hard = data["material"]
    layout = static_curl(data, out / "check", out / "design" / "layout.msh",
                         [soft, dict(hard, where={"group": "hard"})])
    print(f"  re-solved as a plain static scene of layout.msh: {layout:.2f} deg")
    plain = static_curl(data, out / "soft", SCENE.parent / data["mesh"]["file"], [soft])
    print(f"  all in the soft silicone: {plain:.2f} deg")
    print(f"  to cast (halves: mirror in y = 0): {out / 'design' / 'placed.stl'}, {out / 'design' / 'body.stl'}; "
          f"picture: {out / 'design' / 'layout.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "pneunet_layout_out"))
