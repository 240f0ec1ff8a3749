"""Run demos and store what the manual's tutorial pages show: the printed output (docs/demos/<name>.txt) and
the pictures (docs/demos/<name>/*.png, *.gif, scaled down to at most 900 px wide), and a screenshot of the report.html
it wrote (headless Chromium, as the browser tests).

    .venv/bin/python docs/refresh_demos.py            # every demo (about 10 minutes on 2 cores)
    .venv/bin/python docs/refresh_demos.py bent_spoon struck_bar

The test suite checks that the committed transcripts are current (docs/demo_transcripts.py); run this after
changing what a demo prints, and commit docs/demos/.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from PIL import Image

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS))
from demo_transcripts import REPORT_SHOT, TRANSCRIPTS, normalise, transcript_path  # noqa: E402

WIDTH = 900                    # px: pictures wider than this are scaled down
MAX_GIF = 2_500_000            # bytes: larger animations are scaled down by a further factor of 2


def pictures(out: Path) -> list[Path]:
    """The pictures a demo wrote, anywhere under its output folder."""
    return sorted(p for p in out.rglob("*") if p.suffix in (".png", ".gif"))


def store_picture(src: Path, dest: Path) -> None:
    """A copy of src at most WIDTH px wide (animated GIFs keep their frames)."""
    im = Image.open(src)
    if src.suffix == ".png":
        if im.width > WIDTH:
            im = im.resize((WIDTH, round(im.height * WIDTH / im.width)), Image.LANCZOS)
        im.convert("RGB").quantize(256).save(dest, optimize=True)      # plots: 256 colours, a third the bytes
        return
    scale = min(1.0, WIDTH / im.width)
    if src.stat().st_size * scale * scale > MAX_GIF:
        scale /= 2
    if scale == 1.0:
        shutil.copyfile(src, dest)
        return
    size = (round(im.width * scale), round(im.height * scale))
    frames, durations = [], []
    for i in range(getattr(im, "n_frames", 1)):
        im.seek(i)
        frames.append(im.convert("RGB").resize(size, Image.LANCZOS).convert("P", palette=Image.ADAPTIVE))
        durations.append(im.info.get("duration", 100))
    frames[0].save(dest, save_all=True, append_images=frames[1:], duration=durations, loop=0, optimize=True)


def report_shot(out: Path, dest: Path) -> bool:
    """A screenshot of the demo's report.html (the one nearest its output folder's top) by headless Chromium, as
    the browser tests take theirs; False where the demo wrote none (or Chromium is missing)."""
    pages = sorted(out.rglob("report.html"), key=lambda p: (len(p.parts), str(p)))
    chromium = shutil.which("chromium")
    if not pages or chromium is None:
        return False
    shot = out / "report_shot.png"
    try:
        subprocess.run([chromium, "--headless=new", "--no-sandbox", "--use-angle=swiftshader",
                        "--enable-unsafe-swiftshader", "--virtual-time-budget=8000", "--hide-scrollbars",
                        "--window-size=1000,700", f"--screenshot={shot}", pages[0].as_uri()],
                       capture_output=True, timeout=120)
    except subprocess.TimeoutExpired:
        return False
    if not shot.is_file():
        return False
    with Image.open(shot) as im:              # full colour: 256 would shift the marks' and the bar's colours
        im = im.convert("RGB")
        im.resize((WIDTH, round(im.height * WIDTH / im.width)), Image.LANCZOS).save(dest, optimize=True)
    shot.unlink()
    return True


def refresh(name: str) -> float:
    """Run demos/<name>.py, store its transcript and pictures; returns its wall time."""
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OPENBLAS_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / name
        t0 = time.perf_counter()
        p = subprocess.run([sys.executable, str(ROOT / "demos" / f"{name}.py"), str(out)], cwd=tmp, env=env,
                           capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if p.returncode != 0:
            raise SystemExit(f"demos/{name}.py exited {p.returncode}:\n{p.stdout}\n{p.stderr}")
        transcript_path(name).write_text(normalise(p.stdout, out, name))
        folder = TRANSCRIPTS / name
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
        for src in pictures(out):
            store_picture(src, folder / "_".join(src.relative_to(out).parts))
        report_shot(out, folder / REPORT_SHOT)
    return wall


def main(names: list[str]) -> None:
    TRANSCRIPTS.mkdir(exist_ok=True)
    names = names or sorted(p.stem for p in (ROOT / "demos").glob("*.py"))
    for name in names:
        print(f"{name}: {refresh(name):.0f} s", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
