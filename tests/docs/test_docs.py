"""The documentation: the README a newcomer reads first, and the site (mkdocs.yml, docs/).

The scenario format reference is generated from the schema (scripts/gen_docs.py) and must equal
the committed page; the site builds with --strict through the command the README shows
(./docs.sh build); every package has a README and a page that includes it. No ROS needed.
"""
import importlib.util
import os
import re
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SRC = os.path.join(ROOT, "ros_ws", "src")
README = os.path.join(ROOT, "README.md")


def _gen_docs():
    spec = importlib.util.spec_from_file_location("gen_docs", os.path.join(ROOT, "scripts", "gen_docs.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


def test_references_are_generated_from_the_schema_and_the_parameter_tables():
    gen = _gen_docs()
    for page, text in gen.pages().items():
        assert _read(page) == text, f"{os.path.relpath(page, ROOT)} is stale: python scripts/gen_docs.py"


def test_parameter_reference_covers_every_node_parameter():
    gen = _gen_docs()
    page = _read(gen.PARAMETERS_PAGE)
    for table in gen.node_tables().values():
        for p in table:
            assert f"| `{p.name}` | {p.ros_type} |" in page, (table.node, p.name)
    assert "| `marker_rate` | double | `10.0` | 0.1 to 1000 | Hz | live |" in page


def test_topic_reference_covers_every_topic():
    gen = _gen_docs()
    page = _read(gen.TOPICS_PAGE)
    for topic in ("/clock", "/sim/step", "/tf_static", "/<vessel>/odom", "/<vessel>/thruster_command",
                  "/<rope>/end_<a|b>/wrench", "/<rope>/end_<a|b>/coupling", "/<rope>/winch", "/<contact>/state"):
        assert f"| `{topic}` |" in page, topic


def test_scenario_reference_covers_every_key():
    """Every section and key of the schema, with the limits the schema states."""
    gen = _gen_docs()
    page = _read(gen.PAGE)
    for model, _path in gen._walk(gen.SCHEMA):
        assert f"{{#{model.__name__.lower()}}}" in page, model.__name__
        for name in model.model_fields:
            assert f"| `{name}` |" in page, (model.__name__, name)
    assert "| `duration` | number | required | > 0, ≤ 1e7 |" in page
    assert "| `exchange_rate` | number | `50` | ≥ 1, ≤ 1000 |" in page
    assert "| `host` | string | `\"127.0.0.1\"` | length 1 to 253 |" in page


def test_gen_docs_check_reports_a_stale_page(tmp_path, monkeypatch, capsys):
    gen = _gen_docs()
    stale = tmp_path / "scenario-format.md"
    stale.write_text(gen.render().replace("| `duration` |", "| `duration_s` |"), encoding="utf-8")
    monkeypatch.setattr(gen, "PAGE", str(stale))
    monkeypatch.setattr(gen, "PARAMETERS_PAGE", str(tmp_path / "node-parameters.md"))
    monkeypatch.setattr(gen, "TOPICS_PAGE", str(tmp_path / "topics.md"))
    assert gen.main(["--check"]) == 1
    assert "duration_s" in capsys.readouterr().out
    assert gen.main([]) == 0 and gen.main(["--check"]) == 0


def test_readme_is_short_and_its_links_resolve():
    text = _read(README)
    assert len(text.splitlines()) < 200
    for command in ("./run.sh", "./test.sh", "./docs.sh", "./docs.sh build"):
        assert command in text, command
    links = re.findall(r"\]\(([^)]+)\)", text)
    assert any(link.endswith(".png") for link in links), "a picture"
    local = [link.split("#")[0] for link in links if not re.match(r"[a-z]+:", link)]
    missing = [link for link in local if not os.path.exists(os.path.join(ROOT, link))]
    assert local and not missing, missing


def test_every_package_has_a_readme_and_a_page():
    packages = sorted(d for d in os.listdir(SRC) if os.path.isfile(os.path.join(SRC, d, "package.xml")))
    assert len(packages) >= 11
    for package in packages:
        assert os.path.isfile(os.path.join(SRC, package, "README.md")), package
        page = _read(os.path.join(ROOT, "docs", "packages", f"{package}.md"))
        assert f'--8<-- "ros_ws/src/{package}/README.md"' in page, package


def test_site_builds_strict(tmp_path):
    """./docs.sh build: the reference is current and mkdocs build --strict finds every page, link,
    anchor, image and included README (any warning fails)."""
    site = tmp_path / "site"
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    proc = subprocess.run(["./docs.sh", "build", "--site-dir", str(site)], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "WARNING" not in proc.stderr, proc.stderr[-3000:]
    # the README's images render from the pages that now hold them
    benchmarks = _read(site / "benchmarks.html")
    assert 'src="bench_scale.png"' in benchmarks and (site / "bench_scale.png").is_file()
    models = _read(site / "models-and-validation.html")
    for image in ("figures/default_demo_tracks.png", "escort_forces.png"):
        assert f'src="{image}"' in models and (site / image).is_file(), image
    assert models.count("<table") == 3
    reference = _read(site / "reference" / "scenario-format.html")
    gen = _gen_docs()
    assert reference.count("<table") == len(gen._walk(gen.SCHEMA))
    assert 'href="#vesselspec"' in reference and 'id="vesselspec"' in reference
    # a package page holds its README
    assert "towing rope as a chain of rigid elements" in _read(site / "packages" / "rope_model.html")
