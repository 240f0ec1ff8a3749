"""Speed against accuracy for three scenes: `fem-forms study` on each (degrees 1 and 2, three mesh
levels), collected into one markdown file for the manual's "choosing speed or accuracy" page
(docs/speed-accuracy.md includes it).

Run: `.venv/bin/python benchmarks/speed_accuracy.py` (a few minutes). Writes benchmarks/speed_accuracy.md
and the study folders under out/speed_accuracy/.
"""
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
SCENES = [("beam_gravity.toml", ["1", "2"]), ("modal_beam.toml", ["1", "2"]),
          ("incompressible_block.toml", ["2"])]


def main() -> None:
    out = HERE.parent / "out" / "speed_accuracy"
    parts = []
    for name, degrees in SCENES:
        folder = out / name.replace(".toml", "")
        cmd = [sys.executable, "-m", "fem_forms", "study", str(HERE / "scenes" / name), "--out", str(folder),
               "--degrees", *degrees, "--refine", "3"]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            parts.append(f"### {name}\n\nstudy failed: {p.stderr.strip().splitlines()[-1:]}\n")
            continue
        parts.append((folder / "study.md").read_text().replace("# ", "### ", 1))
        print(parts[-1], flush=True)
    (HERE / "speed_accuracy.md").write_text("\n".join(parts))


if __name__ == "__main__":
    main()
