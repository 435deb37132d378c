"""The README's quick start is what CI runs, and it lists every command."""

from pathlib import Path

from tiremodal_cli.cli.main import cli

ROOT = Path(__file__).resolve().parents[1]


def quick_start_commands():
    text = (ROOT / "README.md").read_text()
    section = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    blocks = section.split("```")[1::2]
    return [b.strip() for b in blocks]


def test_two_commands_and_ci_runs_them_verbatim():
    cmds = quick_start_commands()
    assert len(cmds) == 2 and all("\n" not in c for c in cmds)
    ci = (ROOT / ".ci" / "run").read_text()
    assert cmds[0] in ci and cmds[1] in ci
    assert ci.index(cmds[0].split(" && ")[-1]) < ci.index(cmds[1].split(" && ")[-1])
    assert "pytest" in cmds[1]


def test_readme_lists_every_command():
    text = (ROOT / "README.md").read_text()
    for name in cli.commands:
        assert f"`tiremodal {name}" in text, name


def _layout_block():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = text.split("## Layout", 1)[1].split("```", 2)[1]
    listed, pkg = {}, None
    for line in block.splitlines():
        words = line.split()
        if not words or not line.startswith("  "):
            continue
        if words[0].endswith("/") and not words[0].startswith("("):
            pkg = words[0].rstrip("/")
            words = words[1:]
        elif line.startswith("  ") and not line.startswith("      ") and words[0].endswith(".py"):
            pkg = ""
        listed.setdefault(pkg, set()).update(w for w in words if w.endswith(".py"))
    return listed


def test_readme_layout_matches_the_tree():
    """Every module of the package is named in the README's layout, and nothing else."""
    root = ROOT / "tiremodal_cli"
    tree = {}
    for p in root.rglob("*.py"):
        if "__pycache__" in p.parts:
            continue
        rel = p.relative_to(root)
        pkg = "/".join(rel.parts[:-1])
        if rel.name == "__init__.py" and pkg:
            continue
        tree.setdefault(pkg, set()).add(rel.name)
    assert _layout_block() == tree
