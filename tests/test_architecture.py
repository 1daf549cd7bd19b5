"""The package's structure, checked: an acyclic import graph, one place for neighbour lists and
the time loop, one definition of the excitation, a layout that lists every subpackage."""

import ast
import pathlib
import re

import jaxdamp

ROOT = pathlib.Path(jaxdamp.__file__).parent


def _modules():
    out = {}
    for p in ROOT.rglob("*.py"):
        rel = p.relative_to(ROOT.parent).with_suffix("")
        name = ".".join(rel.parts)
        out[name[: -len(".__init__")] if name.endswith(".__init__") else name] = p
    return out


def _import_graph():
    """Every import of a jaxdamp module by a jaxdamp module, at any depth (module level and
    inside functions alike)."""
    mods = _modules()
    edges = {m: set() for m in mods}
    for m, p in mods.items():
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level:
                raise AssertionError(f"{m}: relative import (use absolute jaxdamp.* imports)")
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("jaxdamp"):
                for a in node.names:
                    full = f"{node.module}.{a.name}"
                    target = full if full in mods else node.module
                    if target in mods and target != m:
                        edges[m].add(target)
            elif isinstance(node, ast.Import):
                for a in node.names:
                    if a.name in mods and a.name != m:
                        edges[m].add(a.name)
    return edges


def test_import_graph_has_no_cycles():
    edges = _import_graph()
    state, stack, cycles = {}, [], []

    def visit(v):
        state[v] = "open"
        stack.append(v)
        for w in sorted(edges[v]):
            if state.get(w) == "open":
                cycles.append(stack[stack.index(w):] + [w])
            elif w not in state:
                visit(w)
        stack.pop()
        state[v] = "done"

    for v in sorted(edges):
        if v not in state:
            visit(v)
    assert not cycles, "import cycles: " + "; ".join(" -> ".join(c) for c in cycles)


def test_neighbour_lists_are_allocated_by_the_driver_only():
    """``neighbors.allocate`` is called in the driver and nowhere else in the package."""
    callers = [str(p.relative_to(ROOT)) for p in ROOT.rglob("*.py")
               if re.search(r"\bnb\.allocate\(|neighbors\.allocate\(", p.read_text())]
    assert callers == ["engine/driver.py"], callers


def test_the_excitation_is_written_once():
    """``U cos Ωt`` and the drive ``A_d cos Ωt`` are typed in physics/excitation.py only
    (both engines and both S3 models take them from there)."""
    pat = re.compile(r"(\bU\b|amplitude|amp)\s*\*\s*(jnp|math|np)\.cos\(")
    where = [str(p.relative_to(ROOT)) for p in ROOT.rglob("*.py") if pat.search(p.read_text())
             and not str(p).endswith("physics/excitation.py")]
    assert where == [], where


def test_the_package_docstring_lists_every_subpackage():
    subpackages = sorted(p.parent.name for p in ROOT.glob("*/__init__.py"))
    doc = jaxdamp.__doc__
    missing = [s for s in subpackages if f"jaxdamp.{s}" not in doc]
    assert not missing, missing
