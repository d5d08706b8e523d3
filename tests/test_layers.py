# SPDX-License-Identifier: LGPL-2.1-or-later
"""The Python package's rooms and the direction of its imports, read from the sources.

    kernel < io < fem < peers < compare < freecad < gui, cli

A module imports only its own room and the rooms below it; nothing imports gui (FreeCAD does,
through InitGui.py) except the document object attaching its view provider when FreeCAD's GUI
is up; no circle among module-level imports; and no import inside a function except of FreeCAD,
an optional program or library that may be missing (matplotlib, rich, gmsh, netgen, Dask's
distributed), or the FreeCAD layer from the package's facade (``FemBspTet.make_mesher`` and friends), or of the compiled
core (its loader says how to build it when it is missing)."""

import ast
import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGE = os.path.join(ROOT, "FemBspTet")
LAYERS = {"kernel": 0, "io": 1, "fem": 2, "peers": 3, "compare": 4, "freecad": 5, "gui": 6,
          "cli": 6}
#: modules at the paths older FreeCAD documents store; each re-exports one class
OLD_PATHS = {"FemBspTet.mesher_object", "FemBspTet.view_provider"}
#: the one upward import allowed, inside a function, when FreeCAD's GUI is up
GUI_ATTACH = {("FemBspTet.freecad.mesher_object", "FemBspTet.gui.view_provider")}
#: the compiled modules (the core; the FEM pipeline from CAD, which loads OpenCASCADE)
NATIVE_MODULES = ("_bsptet", "_bsptet_cad")
#: the command line imports what each command needs when that command runs, so that a surface
#: file meshes without loading the CAD, FreeCAD, comparison and picture modules (start-up time)
COMMAND_DISPATCH = {"FemBspTet.cli.main"}
#: top-level modules that may be missing, so are imported where they are used
OPTIONAL = ("FreeCAD", "FreeCADGui", "Part", "Fem", "FemGui", "ObjectsFem", "femmesh", "femtools",
            "femobjects", "femviewprovider", "femtaskpanels", "femguiutils", "PySide", "PySide2",
            "pivy", "matplotlib", "mpl_toolkits", "rich", "gmsh", "netgen", "distributed", "Mesh",
            "MeshPart")


def modules():
    out = {}
    for dirpath, dirnames, filenames in os.walk(PACKAGE):
        dirnames[:] = [d for d in dirnames if d != "__pycache__"]
        for name in filenames:
            if name.endswith(".py"):
                path = os.path.join(dirpath, name)
                dotted = os.path.relpath(path[:-3], ROOT).replace(os.sep, ".")
                if dotted.endswith(".__init__"):
                    dotted = dotted[:-len(".__init__")]
                out[dotted] = path
    return out


def resolve(module, is_package, node):
    if node.level == 0:
        return node.module or ""
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    if node.level > 1:
        base = base[:len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imports_of(module, path):
    """(target, inside a function, line) of every import of ``module``."""
    tree = ast.parse(open(path, encoding="utf-8").read())
    is_package = path.endswith("__init__.py")
    inside = set()
    for fn in ast.walk(tree):
        if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            inside.update(id(n) for n in ast.walk(fn) if n is not fn)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(a.name, id(node) in inside, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            target = resolve(module, is_package, node)
            submodules = [a.name for a in node.names if a.name in NATIVE_MODULES or os.path.exists(
                os.path.join(ROOT, *target.split("."), a.name + ".py")) or os.path.isdir(
                os.path.join(ROOT, *target.split("."), a.name))]
            if submodules:  # from package import module
                found += [(f"{target}.{name}", id(node) in inside, node.lineno)
                          for name in submodules]
            if len(submodules) < len(node.names):
                found.append((target, id(node) in inside, node.lineno))
    return found


def room(dotted):
    parts = dotted.split(".")
    if len(parts) >= 2 and parts[1] in LAYERS:
        return LAYERS[parts[1]]
    return 0  # the package facade, its version and the compiled core: the kernel's level


def known(target, mods):
    """The module of ours that ``target`` names (a module, or a name inside one), or None."""
    if target in {"FemBspTet." + name for name in NATIVE_MODULES}:
        return target
    while target:
        if target in mods:
            return target
        target = target.rpartition(".")[0]
    return None


def test_imports_flow_downward_and_stay_at_module_level():
    mods = modules()
    problems = []
    for module, path in sorted(mods.items()):
        if module in OLD_PATHS:
            continue
        for target, in_function, line in imports_of(module, path):
            where = f"{os.path.relpath(path, ROOT)}:{line}"
            ours = known(target, mods) if target.startswith("FemBspTet") else None
            if ours is None:
                if in_function and not target.startswith("FemBspTet") and \
                        target.split(".")[0] not in OPTIONAL:
                    problems.append(f"{where}: imports {target} inside a function")
                continue
            if (module, ours) in GUI_ATTACH:
                assert in_function, f"{where}: the view provider must be imported only when needed"
                continue
            if in_function and (module == "FemBspTet" or ours.rpartition(".")[2] in NATIVE_MODULES):
                continue  # the FreeCAD layer on demand; the compiled modules, which may be unbuilt
            if in_function and module not in COMMAND_DISPATCH:
                problems.append(f"{where}: imports {ours} inside a function")
            if room(ours) > room(module):
                problems.append(f"{where}: {module} imports {ours}, a room above it")
            if ours.startswith("FemBspTet.gui") and not module.startswith("FemBspTet.gui"):
                problems.append(f"{where}: {module} imports the GUI ({ours})")
    assert not problems, "\n".join(problems)


def test_no_circle_among_module_level_imports():
    mods = modules()
    graph = {m: set() for m in mods}
    for module, path in mods.items():
        for target, in_function, _ in imports_of(module, path):
            ours = known(target, mods) if target.startswith("FemBspTet") else None
            if ours and not in_function and ours != module:
                graph[module].add(ours)
                # importing a.b.c runs the packages a.b and a first
                parent = ours.rpartition(".")[0]
                while parent and parent in mods and not (module + ".").startswith(parent + "."):
                    graph[module].add(parent)
                    parent = parent.rpartition(".")[0]
    state, stack = {}, []

    def visit(m):
        state[m] = "open"
        stack.append(m)
        for n in sorted(graph[m]):
            if state.get(n) == "open":
                raise AssertionError("circle: " + " -> ".join(stack[stack.index(n):] + [n]))
            if n not in state:
                visit(n)
        stack.pop()
        state[m] = "done"

    for m in sorted(graph):
        if m not in state:
            visit(m)


def test_the_rooms_exist_and_old_document_paths_still_import():
    for name in LAYERS:
        assert os.path.isfile(os.path.join(PACKAGE, name, "__init__.py")), name
    from FemBspTet.mesher_object import MeshBspTet
    from FemBspTet.freecad.mesher_object import MeshBspTet as Moved

    assert MeshBspTet is Moved
