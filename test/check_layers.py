#!/usr/bin/env python3
"""The layering rules of docs/architecture.md ("Layers"), held against every #include of lib/ and
cli/. Usage: check_layers.py SOURCE_DIR CORE_LAYER_TXT (or --self-test: each rule against a tree that
breaks it). Exit 0 when every rule holds, 1 with one
line per violation otherwise.

Rules:
  core       every file a core source includes, transitively, is a core file: a core source
             (CORE_LAYER_TXT, written by lib/CMakeLists.txt from the fivebar::core sources) or one
             of CORE_HEADERS below; so the core never reaches a study, a product or the scene;
  cli        nothing in lib/ includes a file of cli/;
  scene      the product registry (lib/src/products/) and the scene are included only by product
             glue (lib/src/<study>/product.cpp), the registry itself and the scene: no study calls
             the scene, and no study or product reaches into another product's glue;
  walls      each heavy dependency's headers are included only in the files of its wall;
  runtime    the device's loop (lib/src/runtime/, fivebar/runtime/) includes nothing of the project
             outside itself: it builds and installs alone (docs/runtime.md);
  device     the chain from a design to the device: device configuration (lib/src/device/,
             fivebar/device/) < simulate (lib/src/simulate/, fivebar/dynamics.hpp) < control
             (lib/src/control/, fivebar/control.hpp, fivebar/control/) < export (lib/src/export/,
             fivebar/export/): no file of a floor includes a file of a floor above it, so the
             export's gate runs simulate on the configuration it writes without a loop back
             (product glue, lib/src/<study>/product.cpp, may reach up: it serves the scene);
  cycles     no include cycle among the project's files.
"""
import os
import re
import sys
from fnmatch import fnmatch

# Headers of the core's layer (public under lib/include, private under lib/src).
CORE_HEADERS = [
    "lib/include/fivebar/design.hpp", "lib/include/fivebar/error.hpp", "lib/include/fivebar/format.hpp",
    "lib/include/fivebar/ranges.hpp", "lib/include/fivebar/version.hpp", "lib/include/fivebar/numerics.hpp", "lib/include/fivebar/suggest.hpp",
    "lib/include/fivebar/csv_reader.hpp",
    "lib/include/fivebar/kinematics.hpp", "lib/include/fivebar/detail/*.hpp",
    "lib/include/fivebar/workspace/region.hpp", "lib/include/fivebar/workspace/polyline.hpp",
    "lib/include/fivebar/coverage/coverage.hpp", "lib/include/fivebar/sections/*.hpp",
    "lib/include/fivebar/design/*.hpp", "lib/include/fivebar/resources/budget.hpp",
    "lib/src/design/*.hpp", "lib/src/kinematics/*.hpp", "lib/src/sections/*.hpp", "lib/src/sections/*.def",
    "lib/src/cgal/exact_region.hpp", "lib/src/yaml/key_path.hpp",
]

# Heavy dependencies: the include prefix and the only files that may include it.
WALLS = {
    "yaml-cpp": (r"yaml-cpp/", ["lib/src/yaml/*"]),
    "CGAL": (r"CGAL/", ["lib/src/cgal/*"]),
    "VTK": (r"vtk", ["lib/src/vtk/*"]),
    "cairo": (r"cairo", ["lib/src/plot/*", "lib/src/*/*_plot.cpp"]),
    "MPI": (r"mpi\.h", ["lib/src/mpi/*"]),
    "SUNDIALS": (r"(cvode|arkode|ida|sundials|nvector|sunmatrix|sunlinsol)/", ["lib/src/simulate/cvode.cpp", "lib/src/simulate/arkode.cpp"]),
    "NLopt": (r"nlopt", ["lib/src/control/control_tune.cpp", "lib/src/optimize/optimize_search.cpp"]),
    "pagmo2": (r"pagmo/", ["lib/src/optimize/optimize_search.cpp"]),
    "quadmath": (r"quadmath", ["lib/src/report/quad.*"]),
    "CLI11": (r"CLI/", ["cli/*"]),
    "cmark-gfm": (r"cmark-gfm", ["lib/src/products/html.cpp"]),
    "Ceres": (r"ceres/", ["lib/src/calibrate/fit.cpp", "lib/src/identify/ceres_output_error.cpp"]),
    "MuJoCo": (r"mujoco/", []),
    "cpp-httplib": (r"httplib\.h", ["cli/studio.cpp"]),
}

# The device chain, bottom floor first: (name, path prefixes).
DEVICE_FLOORS = [
    ("device", ("lib/src/device/", "lib/include/fivebar/device/")),
    ("simulate", ("lib/src/simulate/", "lib/include/fivebar/dynamics.hpp")),
    ("control", ("lib/src/control/", "lib/include/fivebar/control.hpp", "lib/include/fivebar/control/")),
    ("export", ("lib/src/export/", "lib/include/fivebar/export/")),
]


def device_floor(p):
    for i, (_, prefixes) in enumerate(DEVICE_FLOORS):
        if p.startswith(prefixes):
            return i
    return None


INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^">]+)[">]', re.M)


def main():
    root = os.path.abspath(sys.argv[1])
    core_sources = set()
    with open(sys.argv[2]) as f:
        for line in f:
            line = line.strip()
            if line:
                core_sources.add(os.path.relpath(line, root))

    files = {}
    for top in ("lib", "cli"):
        for d, _, names in os.walk(os.path.join(root, top)):
            for n in names:
                if n.endswith((".cpp", ".hpp", ".h", ".def")):
                    p = os.path.relpath(os.path.join(d, n), root)
                    with open(os.path.join(root, p), encoding="utf-8") as fh:
                        files[p] = fh.read()

    def resolve(src, name):
        for base in (os.path.dirname(src), "lib/include", "lib/src"):
            p = os.path.normpath(os.path.join(base, name))
            if p in files:
                return p
        return None

    quoted = {}
    system = {}
    for p, text in files.items():
        quoted[p] = []
        system[p] = []
        for kind, name in INCLUDE.findall(text):
            if kind == '"':
                r = resolve(p, name)
                if r is not None:
                    quoted[p].append(r)
            else:
                system[p].append(name)

    errors = []
    is_core = lambda p: p in core_sources or any(fnmatch(p, g) for g in CORE_HEADERS)

    # core
    seen = set()
    stack = [(p, [p]) for p in sorted(core_sources) if p in files]
    while stack:
        p, path = stack.pop()
        for q in quoted.get(p, []):
            if not is_core(q):
                errors.append("core: " + " -> ".join(path + [q]) + ": not a core file")
            elif q not in seen:
                seen.add(q)
                stack.append((q, path + [q]))

    # cli
    for p in files:
        if p.startswith("lib/"):
            for q in quoted[p]:
                if q.startswith("cli/"):
                    errors.append("cli: " + p + " includes " + q)

    # scene
    scene_files = {"lib/include/fivebar/scene.hpp", "lib/src/scene.cpp"}
    for p in files:
        if not p.startswith("lib/"):
            continue
        glue = p.startswith("lib/src/products/") or p in scene_files or re.fullmatch(r"lib/src/[^/]+/product\.cpp", p)
        for q in quoted[p]:
            reaches = q.startswith("lib/src/products/") or q in scene_files or re.fullmatch(r"lib/src/[^/]+/product\.cpp", q)
            if reaches and not glue:
                errors.append("scene: " + p + " includes " + q + " (only product glue, the registry and the scene may)")

    # runtime
    in_runtime = lambda p: p.startswith(("lib/src/runtime/", "lib/include/fivebar/runtime"))
    for p in files:
        if in_runtime(p):
            for q in quoted[p]:
                if not in_runtime(q):
                    errors.append("runtime: " + p + " includes " + q)

    # device
    for p in files:
        if re.fullmatch(r"lib/src/[^/]+/product\.cpp", p):
            continue
        floor = device_floor(p)
        if floor is None:
            continue
        for q in quoted[p]:
            above = device_floor(q)
            if above is not None and above > floor:
                errors.append("device: " + p + " (" + DEVICE_FLOORS[floor][0] + ") includes " + q + " (" +
                              DEVICE_FLOORS[above][0] + ", a floor above)")

    # walls
    for p, names in system.items():
        for name in names:
            for dep, (prefix, allowed) in WALLS.items():
                if re.match(prefix, name) and not any(fnmatch(p, g) for g in allowed):
                    errors.append("walls: " + p + " includes <" + name + "> (" + dep + " is walled in " +
                                  (", ".join(allowed) or "no library file") + ")")

    # cycles
    state = {}
    def visit(p, path):
        state[p] = 1
        for q in quoted[p]:
            if state.get(q) == 1:
                errors.append("cycles: " + " -> ".join(path[path.index(q):] + [q]))
            elif q not in state:
                visit(q, path + [q])
        state[p] = 2
    for p in sorted(files):
        if p not in state:
            visit(p, [p])

    for e in sorted(set(errors)):
        print(e)
    print(f"{len(files)} files, {sum(len(v) for v in quoted.values())} project includes, "
          f"{len(core_sources)} core sources: {len(set(errors))} violation(s)", file=sys.stderr)
    return 1 if errors else 0


def self_test():
    """Each rule fails on a small tree that breaks it, and passes on one that does not."""
    import subprocess
    import tempfile
    def tree(files, core):
        d = tempfile.mkdtemp(prefix="check_layers.")
        for path, text in files.items():
            os.makedirs(os.path.join(d, os.path.dirname(path)), exist_ok=True)
            with open(os.path.join(d, path), "w") as f:
                f.write(text)
        with open(os.path.join(d, "core_layer.txt"), "w") as f:
            f.write("".join(os.path.join(d, c) + "\n" for c in core))
        r = subprocess.run([sys.executable, __file__, d, os.path.join(d, "core_layer.txt")],
                           capture_output=True, text=True)
        return r.returncode, r.stdout
    good = {
        "lib/src/design/design.cpp": '#include "fivebar/design.hpp"\n',
        "lib/include/fivebar/design.hpp": "#pragma once\n",
        "lib/src/tolerance/tolerance.cpp": '#include "fivebar/design.hpp"\n',
        "lib/src/tolerance/product.cpp": '#include "products/product.hpp"\n',
        "lib/src/products/product.hpp": '#include "fivebar/scene.hpp"\n',
        "lib/include/fivebar/scene.hpp": "#pragma once\n",
        "cli/main.cpp": '#include "fivebar/scene.hpp"\n#include <CLI/CLI.hpp>\n',
    }
    core = ["lib/src/design/design.cpp"]
    cases = [
        ("clean", {}, 0, ""),
        ("core", {"lib/src/design/design.cpp": '#include "fivebar/tolerance.hpp"\n',
                  "lib/include/fivebar/tolerance.hpp": "#pragma once\n"}, 1, "core: "),
        ("cli", {"lib/src/tolerance/tolerance.cpp": '#include "../../../cli/main.cpp"\n'}, 1, "cli: "),
        ("scene", {"lib/src/tolerance/tolerance.cpp": '#include "fivebar/scene.hpp"\n'}, 1, "scene: "),
        ("walls", {"lib/src/tolerance/tolerance.cpp": "#include <pagmo/pagmo.hpp>\n"}, 1, "walls: "),
        ("device", {"lib/src/simulate/inputs.cpp": '#include "fivebar/export/export.hpp"\n',
                    "lib/include/fivebar/export/export.hpp": "#pragma once\n"}, 1, "device: "),
        ("device glue", {"lib/src/simulate/product.cpp": '#include "fivebar/export/export.hpp"\n',
                         "lib/include/fivebar/export/export.hpp": "#pragma once\n"}, 0, ""),
        ("cycles", {"lib/src/tolerance/a.hpp": '#include "tolerance/b.hpp"\n',
                    "lib/src/tolerance/b.hpp": '#include "tolerance/a.hpp"\n'}, 1, "cycles: "),
    ]
    failed = 0
    for name, change, code, prefix in cases:
        files = dict(good)
        files.update(change)
        rc, out = tree(files, core)
        ok = rc == code and (prefix == "" or any(line.startswith(prefix) for line in out.splitlines()))
        print(("ok   " if ok else "FAIL ") + name + ": exit " + str(rc) + (" " + out.strip() if out.strip() else ""))
        failed += 0 if ok else 1
    return 1 if failed else 0


if __name__ == "__main__":
    if sys.argv[1:] == ["--self-test"]:
        sys.exit(self_test())
    sys.exit(main())
