"""DESIGN.md's layering, checked on the source: no module imports a layer above its own.

Layers, bottom to top: ``symbolic`` < the ``lyapcheck`` core < ``sweeps`` < ``reports`` <
the Python API (``lyapcheck.api`` and the package's ``__init__``) < the command line
(``lyapcheck.cli``, and the ``__main__`` entry points). Imports are read with :mod:`ast`,
including those inside functions (a lazy import is still a dependency).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.conftest import ROOT

PACKAGES = ("symbolic", "lyapcheck", "sweeps", "reports")
LAYER_NAMES = ("symbolic", "core", "sweeps", "reports", "api", "cli")


def layer_of(module: str) -> int:
    """The layer index of a dotted module name inside the project."""
    parts = module.split(".")
    if parts[-1] == "__main__" or parts[:2] == ["lyapcheck", "cli"]:
        return LAYER_NAMES.index("cli")
    if module in ("lyapcheck", "lyapcheck.api"):
        return LAYER_NAMES.index("api")
    return LAYER_NAMES.index({"symbolic": "symbolic", "lyapcheck": "core", "sweeps": "sweeps",
                              "reports": "reports"}[parts[0]])


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def is_module(name: str) -> bool:
    base = ROOT.joinpath(*name.split("."))
    return base.with_suffix(".py").exists() or (base / "__init__.py").exists()


def project_imports(path: Path) -> list[tuple[int, str]]:
    """(line, imported project module) for every import statement in ``path``."""
    tree = ast.parse(path.read_text(), filename=str(path))
    me = module_name(path)
    package = me if path.name == "__init__.py" else me.rpartition(".")[0]
    found: list[tuple[int, str]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1])
                source = f"{base}.{node.module}" if node.module else base
            else:
                source = node.module or ""
            # "from lyapcheck import exact" imports the module lyapcheck.exact, not the package
            names = [f"{source}.{a.name}" if is_module(f"{source}.{a.name}") else source for a in node.names]
        else:
            continue
        found.extend((node.lineno, n) for n in names if n.split(".")[0] in PACKAGES)
    return found


def sources() -> list[Path]:
    return sorted(p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))


def test_the_layer_map_knows_every_source_file() -> None:
    files = sources()
    assert len(files) > 50
    assert {layer_of(module_name(p)) for p in files} == set(range(len(LAYER_NAMES)))


@pytest.mark.parametrize("path", sources(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_module_imports_a_higher_layer(path: Path) -> None:
    mine = layer_of(module_name(path))
    upward = [f"line {line}: {name} ({LAYER_NAMES[layer_of(name)]})" for line, name in project_imports(path)
              if layer_of(name) > mine]
    assert not upward, f"{path.relative_to(ROOT)} ({LAYER_NAMES[mine]}) imports a higher layer: {upward}"


@pytest.mark.parametrize("path", sources(), ids=lambda p: str(p.relative_to(ROOT)))
def test_only_the_command_line_uses_click(path: Path) -> None:
    if layer_of(module_name(path)) == LAYER_NAMES.index("cli"):
        return
    tree = ast.parse(path.read_text())
    uses = [n.lineno for n in ast.walk(tree)
            if (isinstance(n, ast.Import) and any(a.name.split(".")[0] == "click" for a in n.names))
            or (isinstance(n, ast.ImportFrom) and (n.module or "").split(".")[0] == "click")]
    assert not uses, f"{path.relative_to(ROOT)} imports click (lines {uses}); command-line code lives in lyapcheck.cli"


def test_the_checker_catches_an_upward_import() -> None:
    """The rule is not vacuous: a core module importing sweeps is reported."""
    probe = ROOT / "lyapcheck" / "_layer_probe_tmp.py"
    probe.write_text("def f():\n    from sweeps.run import run_sweep\n    from lyapcheck import exact\n")
    try:
        names = project_imports(probe)
        assert (2, "sweeps.run") in names and (3, "lyapcheck.exact") in names
        assert layer_of("sweeps.run") > layer_of(module_name(probe))
        assert layer_of("lyapcheck.exact") == layer_of(module_name(probe))
    finally:
        probe.unlink()


def import_graph() -> dict[str, set[str]]:
    """Project module -> the project modules its import statements name (lazy ones included)."""
    graph: dict[str, set[str]] = {}
    for path in sources():
        me = module_name(path)
        graph[me] = {name for _, name in project_imports(path) if name != me and is_module(name)}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_import_graph_has_no_cycle() -> None:
    """No two modules import each other, directly or through others, inside a package or across
    (an import inside a function counts: it is still a dependency)."""
    assert cycles(import_graph()) == []


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


# ---- inside the core: the model packages' arrows, as each package's docstring declares them ----

MODEL_PACKAGES = ("language", "engines", "loop", "classes", "surfaces")


def declared_imports(package: str) -> tuple[str, ...]:
    """The prefixes a package's ``__init__`` docstring lists after ``May import:``."""
    doc = ast.get_docstring(ast.parse((ROOT / package.replace(".", "/") / "__init__.py").read_text())) or ""
    _, found, rest = doc.partition("May import:")
    assert found, f"{package}'s docstring does not say what it may import ('May import: ...')"
    return tuple(name.strip() for name in rest.replace("\n", " ").split(",") if name.strip())


def allowed(name: str, own: str, prefixes: tuple[str, ...]) -> bool:
    return any(name == p or name.startswith(p + ".") for p in (own, *prefixes))


@pytest.mark.parametrize("package", MODEL_PACKAGES)
def test_each_model_package_imports_only_what_its_docstring_declares(package: str) -> None:
    own = f"lyapcheck.models.{package}"
    prefixes = declared_imports(own)
    # the declared order is the layering: a package never declares one above it
    above = {f"lyapcheck.models.{p}" for p in MODEL_PACKAGES[MODEL_PACKAGES.index(package):]}
    assert not above & set(prefixes), f"{own} declares a package at or above its own: {above & set(prefixes)}"
    breaches = [f"{path.relative_to(ROOT)} line {line}: {name}"
                for path in sorted((ROOT / own.replace(".", "/")).rglob("*.py"))
                for line, name in project_imports(path)
                if name.startswith("lyapcheck") and not allowed(name, own, prefixes)]
    assert not breaches, f"{own} may import only {prefixes}: {breaches}"


def test_no_generic_module_imports_the_paper() -> None:
    """The generic core (model files, the SOS engine, the integrator, ...) never depends on the paper's
    loop; only the paper's own package, the API and the command line may."""
    breaches = []
    for path in sources():
        me = module_name(path)
        if not me.startswith("lyapcheck") or me.startswith("lyapcheck.paper") or layer_of(me) > layer_of("lyapcheck.exact"):
            continue
        breaches += [f"{me} line {line}: {name}" for line, name in project_imports(path)
                     if name.startswith("lyapcheck.paper")]
    assert not breaches, breaches


def test_the_declared_arrows_are_checked_not_assumed() -> None:
    """The checker is not vacuous: an import the docstring does not list is a breach."""
    prefixes = declared_imports("lyapcheck.models.language")
    assert not allowed("lyapcheck.models.classes.barrier", "lyapcheck.models.language", prefixes)
    assert allowed("lyapcheck.sos.polynomials", "lyapcheck.models.language", prefixes)
