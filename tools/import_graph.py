"""The import graph of the checkout's packages (spreadmap, spreadlab), read with ast, and which of
their modules the product reaches (issue 65).

    python tools/import_graph.py            modules of spreadmap the product does not reach
    python tools/import_graph.py --reached  the ones it does
    python tools/import_graph.py --cycles   import cycles inside spreadmap

The product's entry points: scripts/*.py, the Snakefile and rules/*.smk (their Python imports:
the `script:` files are scripts/*.py); yade_scripts/ runs inside YADE and imports no package.
Every import counts, a function-local one too, since it runs when the function does. Importing
`a.b.c` runs `a` and `a.b` too, so a module's package `__init__` is reached with it (an edge in
the graph unless the package is the importer's own, which is loading already); `from a.b import
c` reaches `a.b.c` when c is a module. A package whose __init__ loads submodules on first use (a
module-level `__getattr__` with `import_module`: spreadmap.surrogate, spreadmap.decisions)
reaches every submodule whose name is a string in it, for --reached (not for --cycles: loading
on first use is after the package has loaded).
"""
from __future__ import annotations

import argparse
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("spreadmap", "spreadlab")


def package_modules(root: Path = ROOT, packages=PACKAGES) -> dict[str, Path]:
    """Dotted module name -> its file, for every .py file of the packages (a package is its
    __init__.py)."""
    modules = {}
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            modules[".".join(parts)] = path
    return modules


def imported_names(tree: ast.AST, modules, module: str | None = None, is_package: bool = False) -> set[str]:
    """The package modules the code imports, at any depth (a function's imports too), relative ones
    resolved against `module`: for `import a.b.c` the longest of a.b.c, a.b, a that is a module; for
    `from a.b import c` a.b.c when it is a module, else the longest module prefix of a.b."""
    names = set()

    def module_of(name):
        parts = name.split(".")
        for i in range(len(parts), 0, -1):
            if ".".join(parts[:i]) in modules:
                return ".".join(parts[:i])
        return None

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(module_of(alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                if module is None:
                    continue
                parts = module.split(".") if is_package else module.split(".")[:-1]
                parts = parts[:len(parts) - (node.level - 1)]
                base = ".".join(parts + ([node.module] if node.module else []))
            else:
                base = node.module
            for alias in node.names:
                names.add(f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules else module_of(base))
    names.discard(None)
    return names


def lazy_names(tree: ast.AST, module: str, modules) -> set[str]:
    """The submodules a package's __init__ loads on first use (a module-level ``__getattr__`` with
    ``import_module``): every string in the __init__ that names one of its submodules."""
    if not any(isinstance(n, ast.FunctionDef) and n.name == "__getattr__" for n in tree.body):
        return set()
    strings = {n.value.strip(".") for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)}
    return {f"{module}.{s}" for s in strings if f"{module}.{s}" in modules}


def parents(name: str) -> list[str]:
    """The packages importing `name` runs first: a.b.c -> [a, a.b]."""
    parts = name.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def graph(root: Path = ROOT, packages=PACKAGES, lazy: bool = False) -> dict[str, set[str]]:
    """Module -> the package modules importing it runs (not itself): those it imports, and their
    packages' __init__ unless they are its own (a module of a package that is loading does not load
    it again); with `lazy`, a package's __init__ also -> the submodules it loads on first use."""
    modules = package_modules(root, packages)
    edges = {}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(), filename=str(path))
        targets = imported_names(tree, modules, name, path.name == "__init__.py")
        own = set(parents(name)) | {name}
        edges[name] = (targets | {p for t in targets for p in parents(t)}) - own
        if lazy and path.name == "__init__.py":
            edges[name] |= lazy_names(tree, name, modules)
    return edges


def entry_point_files(root: Path = ROOT) -> list[Path]:
    """The product's entry points: the Snakemake scripts, the Snakefile and its rule files."""
    return sorted((root / "scripts").glob("*.py")) + [root / "Snakefile"] + sorted((root / "rules").glob("*.smk"))


def entry_point_imports(path: Path, modules) -> set[str]:
    """The package modules a script or a Snakemake file imports (Snakemake's own syntax is not
    Python: its import lines are read one by one)."""
    text = path.read_text()
    if path.suffix == ".py":
        return imported_names(ast.parse(text, filename=str(path)), modules)
    names = set()
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith(("import ", "from ")):
            try:
                names |= imported_names(ast.parse(stripped), modules)
            except SyntaxError:
                continue
    return names


def reached(root: Path = ROOT, packages=PACKAGES) -> set[str]:
    """The package modules the product's entry points reach, directly or through one another."""
    edges = graph(root, packages, lazy=True)
    todo = set()
    for path in entry_point_files(root):
        todo |= entry_point_imports(path, edges)
    seen = set()
    while todo:
        name = todo.pop()
        if name not in seen:
            seen.add(name)
            todo |= (edges[name] | set(parents(name))) - seen
    return seen


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The import graph's strongly connected components of more than one module (Tarjan), each
    sorted: a module importing itself through others. A package's __init__ importing its own
    submodules is an edge like any other."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(start):
        work = [(start, iter(sorted(edges[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(edges[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))

    for name in sorted(edges):
        if name not in index:
            visit(name)
    return found


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reached", action="store_true", help="list the spreadmap modules the product reaches")
    parser.add_argument("--cycles", action="store_true", help="list the import cycles inside spreadmap")
    args = parser.parse_args(argv)
    if args.cycles:
        for component in cycles(graph(packages=("spreadmap",))):
            print(" ".join(component))
        return
    modules = package_modules(packages=("spreadmap",))
    product = reached()
    chosen = sorted(m for m in modules if (m in product) == args.reached)
    lines = {m: len(modules[m].read_text().splitlines()) for m in chosen}
    for name in chosen:
        print(f"{lines[name]:6d}  {name}")
    print(f"{sum(lines.values()):6d}  lines in {len(chosen)} modules")


if __name__ == "__main__":
    main()
