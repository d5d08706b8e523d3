# SPDX-License-Identifier: LGPL-2.1-or-later
"""The C++ layers and the direction of their includes, read from the sources.

Every header and source of a layer (``cpp_module/include/bsptet/X/``, ``cpp_module/src/X/``)
includes only project headers of its own layer and of the layers it may use, directly or through
another layer (docs/design/README.md, "C++ code layout"); the CMake targets link the same way. No
header is left outside a layer folder."""

import os
import re

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CPP = os.path.join(ROOT, "cpp_module")
#: layer -> the layers it uses directly
USES = {
    "numerics": set(),
    "mesh": {"numerics"},
    "input": {"mesh"},
    "core": {"input", "mesh"},
    "refine": {"mesh"},
    "cad": {"mesh"},
    "pieces": {"core"},
    "fem": {"cad", "core", "refine"},
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"bsptet/([^"]+)"', re.M)


def reachable(layer):
    out, todo = set(), [layer]
    while todo:
        for below in USES[todo.pop()]:
            if below not in out:
                out.add(below)
                todo.append(below)
    return out | {layer}


def layer_files():
    for top in (os.path.join(CPP, "include", "bsptet"), os.path.join(CPP, "src")):
        for name in sorted(os.listdir(top)):
            path = os.path.join(top, name)
            if os.path.isfile(path):
                yield None, path
            else:
                for dirpath, _, filenames in os.walk(path):
                    for f in sorted(filenames):
                        yield name, os.path.join(dirpath, f)


def test_every_file_is_in_a_known_layer():
    stray = [os.path.relpath(p, ROOT) for layer, p in layer_files() if layer not in USES]
    assert not stray, "files outside the layer folders: " + ", ".join(stray)


def test_includes_run_downward_only():
    upward = []
    for layer, path in layer_files():
        if layer not in USES:
            continue
        allowed = reachable(layer)
        with open(path, encoding="utf-8") as f:
            text = f.read()
        for target in INCLUDE.findall(text):
            used = target.split("/")[0] if "/" in target else None
            if used not in allowed:
                upward.append(f"{os.path.relpath(path, ROOT)} ({layer}) includes bsptet/{target}")
    assert not upward, "includes that leave the layer's reach:\n" + "\n".join(upward)


def test_cmake_links_match_the_layers():
    targets = {"numerics": "bsptet_numerics", "mesh": "bsptet_mesh_lib", "input": "bsptet_input",
               "core": "bsptet_core", "refine": "bsptet_refine_lib", "cad": "bsptet_cad",
               "pieces": "bsptet_pieces", "fem": "bsptet_fem_pipeline"}
    layer_of = {t: l for l, t in targets.items()}
    with open(os.path.join(CPP, "CMakeLists.txt"), encoding="utf-8") as f:
        cmake = f.read()
    for layer, target in targets.items():
        m = re.search(r"target_link_libraries\(" + target + r" PUBLIC ([^)]*)\)", cmake)
        assert m, f"no target_link_libraries for {target}"
        linked = {layer_of[w] for w in m.group(1).split() if w in layer_of}
        assert linked == USES[layer], f"{target} links {sorted(linked)}, expected {sorted(USES[layer])}"
