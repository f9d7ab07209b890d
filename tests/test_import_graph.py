"""The import graph of ``moor_env`` and ``agents``: no cycles, and imports inside functions only where they keep an
optional or heavy dependency out of the import of a module.

Every module is parsed with :mod:`ast` (nothing is imported). The graph has an edge from a module to every module
of the two packages it imports, at module level or inside a function; ``from package import name`` is an edge to
the submodule ``package.name`` where that is a module, else to the package. Imports under ``if TYPE_CHECKING:``
never run and are left out.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("moor_env", "agents")

# Top-level packages a function may import: optional extras (ray, torch, stable_baselines3, tensorboard, moordyn,
# nbclient) and plotting / image libraries that only drawing needs (matplotlib, Pillow, imageio).
OPTIONAL = {"ray", "moordyn", "matplotlib", "torch", "stable_baselines3", "tensorboard", "nbclient", "PIL", "imageio"}

# Other function-level imports, by (importing module, imported module), with the reason they stay in a function.
ALLOWED: dict[tuple[str, str], str] = {
    ("agents.train", "agents.vec_adapter"):
        "vec_adapter subclasses stable_baselines3's VecEnv at module level, and stable_baselines3 is optional",
    ("agents.evaluate", "scipy"):
        "scipy.stats takes about 0.5 s to import and only the t-interval over training seeds needs it",
}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def package_files() -> dict[str, Path]:
    files = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            files[module_name(path)] = path
    return files


FILES = package_files()


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def imports(module: str, path: Path) -> list[tuple[str, bool, int]]:
    """(imported module, inside a function, line) of every import of a module; ``from a import b`` gives
    ``a.b`` where that is a module of the packages, else ``a``."""
    found: list[tuple[str, bool, int]] = []
    is_package = path.name == "__init__.py"

    def visit(node: ast.AST, in_function: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child):
                for sub in child.orelse:
                    visit(sub, in_function)
                continue
            inner = in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
            if isinstance(child, ast.Import):
                found.extend((alias.name, in_function, child.lineno) for alias in child.names)
            elif isinstance(child, ast.ImportFrom):
                base = child.module or ""
                if child.level:
                    anchor = module.split(".")
                    anchor = anchor[: len(anchor) - child.level + (1 if is_package else 0)]
                    base = ".".join(anchor + ([base] if base else []))
                for alias in child.names:
                    target = f"{base}.{alias.name}"
                    found.append((target if target in FILES else base, in_function, child.lineno))
            visit(child, inner)

    visit(ast.parse(path.read_text(encoding="utf-8")), False)
    return found


IMPORTS = {module: imports(module, path) for module, path in FILES.items()}


def _internal(target: str) -> str | None:
    """The module of the packages that importing ``target`` names (its longest prefix that is one), if any."""
    parts = target.split(".")
    for n in range(len(parts), 0, -1):
        name = ".".join(parts[:n])
        if name in FILES:
            return name
    return None


def graph() -> dict[str, set[str]]:
    edges: dict[str, set[str]] = {module: set() for module in FILES}
    for module, found in IMPORTS.items():
        for target, _, _ in found:
            internal = _internal(target)
            if internal is not None and internal != module:
                edges[module].add(internal)
    return edges


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []

    def connect(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                connect(w)
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
                components.append(sorted(component))

    for v in sorted(edges):
        if v not in index:
            connect(v)
    return components


def test_every_module_is_parsed():
    assert {"moor_env", "moor_env.envs.core", "moor_env.envs.reward", "agents", "agents.evaluate"} <= set(FILES)
    assert all(IMPORTS[m] for m in ("moor_env.envs.core", "agents.evaluate"))


def test_the_graph_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycles():
    found = cycles(graph())
    assert not found, "import cycles: " + "; ".join(" <-> ".join(c) for c in found)


def test_function_level_imports_are_optional_dependencies():
    offending = []
    for module, found in IMPORTS.items():
        for target, in_function, line in found:
            if not in_function or target.split(".")[0] in OPTIONAL:
                continue
            if any(module == m and (target == t or target.startswith(t + ".")) for m, t in ALLOWED):
                continue
            offending.append(f"{FILES[module].relative_to(ROOT)}:{line} imports {target} inside a function")
    assert not offending, "\n".join(offending)


def test_allow_list_entries_are_used():
    used = {(m, t) for (m, t) in ALLOWED
            if any(f and (target == t or target.startswith(t + ".")) for target, f, _ in IMPORTS.get(m, []))}
    assert used == set(ALLOWED), f"unused allow-list entries: {set(ALLOWED) - used}"


def _comment_of(lines: list[str], line: int) -> str:
    """The comments that speak for the import on ``line`` (1-based): on its own line, or on the lines just above
    the group of imports it belongs to."""
    text = lines[line - 1].partition("#")[2]
    first = line - 1
    while first > 0 and lines[first - 1].strip().startswith(("import ", "from ")):
        first -= 1
    above = first - 1
    while above >= 0 and lines[above].strip().startswith("#"):
        text += " " + lines[above].strip()
        above -= 1
    return text


def test_function_level_imports_name_their_dependency_in_a_comment():
    """Every import inside a function says in a comment which optional or heavy dependency it keeps out of the
    module's import (the package's name: ``PIL`` as Pillow) or, for an allow-listed internal one, why."""
    missing = []
    for module, found in IMPORTS.items():
        lines = FILES[module].read_text(encoding="utf-8").splitlines()
        for target, in_function, line in found:
            top = target.split(".")[0]
            if not in_function:
                continue
            comment = _comment_of(lines, line)
            names = {"PIL": ("Pillow", "PIL")}.get(top, (top,))
            if not (any(name in comment for name in names) or (top in PACKAGES and comment.strip())):
                missing.append(f"{FILES[module].relative_to(ROOT)}:{line} imports {target} without a comment "
                               f"naming {names[0]}")
    assert not missing, "\n".join(missing)
