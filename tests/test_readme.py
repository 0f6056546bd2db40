"""The README's examples run, its commands match CI, its parameter table is the declaration's."""

import pathlib
import re

from filter_symblend.parameters import parameters_markdown

ROOT = pathlib.Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def test_python_examples_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for block in re.findall(r"```python\n(.*?)```", README, flags=re.S):
        exec(compile(block, "README.md", "exec"), namespace)
    assert (tmp_path / "cow_symmetrized.ply").exists() and (tmp_path / "cow.pp").exists()


def test_first_commands_are_the_demo_and_the_tests_and_ci_runs_the_second():
    commands = re.findall(r"```\n(.*?)\n```", README.split("## ")[0], flags=re.S)
    assert len(commands) == 2
    assert commands[0].endswith("scripts/demo.py") and "pytest" in commands[1]
    assert commands[1] in (ROOT / ".ci" / "run").read_text().splitlines()


def test_parameter_table_is_generated_from_the_declaration():
    assert parameters_markdown() in README
