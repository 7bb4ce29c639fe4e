"""docs/studies.md as written (no ROS): its study file is the installed example's, its error
message is the one the command prints, and its `--plan` commands list the examples' runs."""
import os

import yaml

from studies import study

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PAGE = os.path.join(ROOT, "docs", "studies.md")


def _blocks(lang=""):
    """The page's fenced blocks of that language (fences read line by line, opening and closing)."""
    out, block, kind = [], None, None
    for line in open(PAGE, encoding="utf-8").read().splitlines():
        if line.startswith("```") and block is None:
            block, kind = [], line[3:].strip()
        elif line.startswith("```"):
            if kind == lang:
                out.append("\n".join(block) + "\n")
            block = None
        elif block is not None:
            block.append(line)
    return out


def test_the_pages_study_file_is_the_example():
    shown = yaml.safe_load(next(b for b in _blocks("yaml") if b.startswith("name: tow_length_engine_order")))
    example = yaml.safe_load(open(study.study_path("tow_length_engine_order.yaml"), encoding="utf-8"))
    for key in ("name", "scenario", "duration", "axes"):
        assert shown[key] == example[key], key
    assert shown["measures"].items() <= example["measures"].items()


def test_the_pages_error_message(tmp_path, capsys, monkeypatch):
    block = next(b for b in _blocks() if b.startswith("$ ros2 run studies study bad.yaml"))
    example = open(study.study_path("tow_length_engine_order.yaml"), encoding="utf-8").read()
    bad = tmp_path / "bad.yaml"
    bad.write_text(example.replace("ropes[towline].deployed_length", "ropes[towline].lenght"))
    monkeypatch.chdir(tmp_path)
    assert study.main(["bad.yaml"]) == 2
    printed = capsys.readouterr().err.splitlines()
    shown = block.splitlines()[1:]
    assert len(printed) == len(shown), printed
    for got, want in zip(printed, shown):
        assert got.endswith(want[3:]) if want.startswith("...") else got == want


def test_the_pages_plan_commands(capsys):
    commands = [line.split() for b in _blocks() for line in b.splitlines() if line.endswith("--plan")]
    assert len(commands) == 2
    runs = []
    for command in commands:
        assert command[:4] == ["ros2", "run", "studies", "study"]
        assert study.main(command[4:]) == 0
        runs.append(len([line for line in capsys.readouterr().out.splitlines() if " configuration " in line]))
    assert runs == [9, 20]
