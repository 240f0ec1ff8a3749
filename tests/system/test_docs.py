"""The manual (docs/): it builds with warnings as errors (a broken link, a link to a scene key that no longer
exists, a demo without its transcript fail), documents every key the scene schema knows at the anchor the
CLI's error messages point to, and the first scene that the README and Getting started show still prints
what they show."""
import importlib.util
import json
import os
import re
import subprocess
import sys

import pytest

from fem_forms.cli import main
from fem_forms.scene.manual import anchor, key_paths, manual_page, pages
from fem_forms.scene.schema import scene_schema
from helpers import ROOT

DOCS = ROOT / "docs"
_spec = importlib.util.spec_from_file_location("demo_transcripts", DOCS / "demo_transcripts.py")
transcripts = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(transcripts)
ENV = dict(os.environ, PYTHONPATH=str(ROOT), OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OPENBLAS_NUM_THREADS="1")


@pytest.fixture(scope="module")
def html(tmp_path_factory):
    """The manual built as the README says (sphinx-build -W), into a temporary folder."""
    out = tmp_path_factory.mktemp("html")
    p = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                        "-d", str(out / ".doctrees"), str(DOCS), str(out)],
                       cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0 and not p.stderr.strip(), f"the manual does not build:\n{p.stdout}\n{p.stderr}"
    return out


def test_manual_builds_and_opens_offline(html):
    index = (html / "index.html").read_text()
    assert "Getting started" in index and (html / "searchindex.js").is_file()
    for page in html.rglob("*.html"):
        text = page.read_text()
        remote = re.findall(r'<(?:script|link|img)[^>]+(?:src|href)="(https?://[^"]+)"', text)
        assert not remote, f"{page.relative_to(html)} loads {remote[0]}: the manual must open offline"
    for name in sorted(p.stem for p in (ROOT / "demos").glob("*.py")):
        page = (html / "tutorials" / f"{name}.html").read_text()
        assert f"demos/{name}.py" in page and "What it prints" in page and "<img" in page, name
        assert "What it is checked against" in page and "tests/system/test_" in page, name
        assert "The scene: <code" in page and ".toml</span></code>" in page, f"{name}: no scene file shown"


def test_every_scene_key_is_in_the_reference_at_its_anchor(html):
    """Walked from the JSON Schema (another walk of the declarations than the one the pages are written
    from): every key has its page and anchor; a selector's shapes are listed under their `where` key."""
    documented = key_paths()
    kinds = {e.path: e.cases[0][0].kind for p in pages() for e in p.entries.values()}
    found = set()

    def walk(s, path):
        if not isinstance(s, dict):
            return
        for name, sub in s.get("properties", {}).items():
            found.add(f"{path}.{name}" if path else name)
            walk(sub, f"{path}.{name}" if path else name)
        for k in ("oneOf", "anyOf", "allOf"):
            for sub in s.get(k, []):
                walk(sub, path)
        for k in ("items", "then"):
            walk(s.get(k), path)

    walk(scene_schema(), "")
    tables = {p.name for p in pages()}
    for path in sorted(found):
        if path in tables:
            continue
        parent = path.rsplit(".", 1)[0]
        if path not in documented:
            assert kinds.get(parent) == "selector", f"scene key {path} is not in the manual's reference"
            continue
        page = html / "reference" / f"{documented[path]}.html"
        assert f'id="{anchor(path)}"' in page.read_text(), f"{path}: no anchor in {page.name}"
    assert len(documented) > 150


def test_a_bad_key_points_to_its_page(html, capsys, monkeypatch, tmp_path):
    monkeypatch.chdir(ROOT)
    scene = tmp_path / "bad.toml"
    scene.write_text('analysis = "modal"\n[mesh]\n[material]\nE = 1.0e6\nnu = 0.3\n[modal]\ncount = 0\n')
    assert main(["run", str(scene), "-q", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    m = re.search(r"\(help: fem-forms help (\S+?)(; manual: docs/_build/html/reference/\w+\.html#\S+)?\)$", err.strip())
    assert m and m.group(1) == "modal.count" and err.count("\n") == 1, err
    page, anchor = manual_page(err.split("error: ", 1)[1]).split("#")
    assert page == "reference/modal.html" and f'id="{anchor}"' in (html / page).read_text()
    assert main(["help", "modal.count"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("modal.count  (manual page: reference/modal)") and "- type: whole number" in text
    assert main(["help", "modal.cont"]) == 2
    assert "help 'modal.cont': no such scene key (did you mean modal.count" in capsys.readouterr().err
    assert manual_page("material[1].where.box: lower corner [1, 0, 0] exceeds upper corner") == \
        "reference/material.html#key-material.where"
    assert manual_page("mesh.cellz: unknown key") == "reference/mesh.html"
    assert manual_page("command line: 'x' is not an option") is None
    assert manual_page("scene file 'a.toml': not found") is None


def test_help_and_schema_name_the_manual(capsys, monkeypatch):
    monkeypatch.chdir(ROOT)
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    assert "docs/_build/html/reference/index.html" in " ".join(capsys.readouterr().out.split())
    assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    assert "docs/_build/html/reference/index.html" in schema["description"]
    assert "reference/sound.html" in schema["properties"]["sound"]["description"]


def test_the_first_scene_prints_what_the_readme_shows(tmp_path):
    scene = (DOCS / "examples" / "first_scene.toml").read_text()
    readme = (ROOT / "README.md").read_text()
    assert scene.strip() in readme, "the README's first scene is not docs/examples/first_scene.toml"
    p = subprocess.run([sys.executable, "-m", "fem_forms", "run", str(DOCS / "examples" / "first_scene.toml"), "-q"],
                       cwd=tmp_path, env=ENV, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    fresh = transcripts.normalise(p.stdout, tmp_path / "out" / "first_scene", "first_scene")
    stored = (DOCS / "examples" / "first_scene.txt").read_text()
    assert transcripts.differences(stored, fresh) == [], (stored, fresh)
    title = re.search(r'title = "([^"]+)"', scene).group(1)
    shown = readme[readme.index(title + ":"):].split("```")[0]
    assert transcripts.differences(shown, fresh) == [], "the README's output of the first scene is stale"


def test_the_readme_quotes_the_verification_manual():
    verified = re.search(r"(\d+) of (\d+) rows pass", (ROOT / "verification" / "README.md").read_text())
    assert verified and f"{verified.group(1)} of {verified.group(2)} rows" in (ROOT / "README.md").read_text()


def test_a_changed_demo_number_makes_its_page_stale():
    """The comparison every demo run goes through (tests/system/demo_runs.py): timings, round-off and a solver
    effort within a quarter pass (17 Newton iterations for 18: last-bit changes move a Newton path at round-off by one);
    a changed count, a digit beyond a rounding flip, an effort beyond a quarter or changed words fail."""
    page = "beam: 3075 dofs, 18 Newton iterations, 4.06 s\n  tip u = (-0.0586, 1.2e-14) m, period 0.866 s\n"
    same = page.replace("4.06 s", "9.31 s").replace("1.2e-14", "-3.5e-15").replace("-0.0586", "-0.0587")
    assert transcripts.differences(page, same) == []
    assert transcripts.differences(page, page.replace("18 Newton", "17 Newton")) == []
    for changed in (page.replace("3075 dofs", "3076 dofs"), page.replace("18 Newton", "27 Newton"),
                    page.replace("-0.0586", "-0.0588"),
                    page.replace("0.866 s", "0.868 s"), page.replace("tip u", "tip v")):
        assert transcripts.differences(page, changed), changed
    # a demo that amplifies round-off (transcripts.ROUNDOFF_AMPLIFIED): values within the fraction pass, not beyond
    rtol = transcripts.ROUNDOFF_AMPLIFIED["rocking_toy"]
    assert transcripts.differences(page, page.replace("0.866 s", f"{0.866 * (1 - rtol / 2):.3f} s"), rtol) == []
    assert transcripts.differences(page, page.replace("0.866 s", f"{0.866 * (1 - 1.5 * rtol):.3f} s"), rtol)
    assert transcripts.differences(page, page.replace("tip u", "tip v"), rtol)
    assert transcripts.differences(page, page.replace("3075 dofs", "3076 dofs"), rtol)      # counts stay exact


def _without_required(s, in_if=False):
    """The schema with no key required (a guide shows a fragment of a scene), except in the conditions that
    tell variants apart (generator = "box" or "file", load type)."""
    if isinstance(s, dict):
        return {k: _without_required(v, in_if or k == "if") for k, v in s.items() if k != "required" or in_if}
    if isinstance(s, list):
        return [_without_required(v, in_if) for v in s]
    return s


def test_every_toml_example_in_the_manual_uses_declared_keys():
    """A key renamed or removed in the code fails here if a guide or the README still shows it."""
    import jsonschema
    import tomllib
    schema = scene_schema()
    schema.pop("allOf")                                   # fragments need not name their analysis
    validator = jsonschema.Draft7Validator(_without_required(schema))
    pages = [p for p in DOCS.rglob("*.md") if not {"reference", "_build"} & set(p.relative_to(DOCS).parts)
             and not (p.parent.name == "tutorials" and p.name != "index.md")] + [ROOT / "README.md"]
    blocks = 0
    for page in pages:
        for m in re.finditer(r"```toml\n(.*?)```", page.read_text(), re.S):
            blocks += 1
            errors = [f"{list(e.absolute_path)}: {e.message[:120]}" for e in validator.iter_errors(tomllib.loads(m.group(1)))]
            assert not errors, f"{page.relative_to(ROOT)}: {errors[0]}"
    assert blocks >= 12
