#!/usr/bin/env bash
# The installed package (docs/install.md), from a build tree: usage
#   check_install.sh BUILD_DIR SOURCE_DIR SCRATCH_DIR VERSION
# installs the components dev, cli and the runtime package's (development, runtime) into SCRATCH/stage,
# moves the tree to a new temporary folder
# (an install must not depend on its prefix), then checks that
#   - the files of docs/install.md are there (config + version file, share/fivebar/{scad,schemas,
#     designs,docs}, completions, a man page per command, licence and citation);
#   - the installed binary names no path of the checkout, and finds the OpenSCAD library beside
#     itself: `parts --no-render` succeeds from an unrelated directory, and fails once
#     share/fivebar/scad is taken away (so nothing compiled in stands behind it);
#   - consumer projects (test/install/consumer) configure, build and run against the moved prefix
#     with nothing but find_package(fivebar COMPONENTS ...): core alone, runtime alone, and full;
#   - the bash completion completes subcommands and options, the zsh one parses, the man pages render.
set -euo pipefail
build=$(cd "$1" && pwd) src=$(cd "$2" && pwd) scratch=$3 version=$4
rm -rf "$scratch"
mkdir -p "$scratch"
scratch=$(cd "$scratch" && pwd)
fail() { echo "check_install: FAIL: $*" >&2; exit 1; }

for component in dev cli development runtime; do
  cmake --install "$build" --prefix "$scratch/stage" --component "$component" > "$scratch/install-$component.log"
done
# Moved out of the build tree too: the data must be found beside the binary, not above it in the
# build tree (whose share/fivebar/ the build-tree binaries use).
moved=$(mktemp -d "${TMPDIR:-/tmp}/fivebar-install.XXXXXX")
trap 'rm -rf "$moved"' EXIT
mv "$scratch/stage" "$moved/prefix"
p=$moved/prefix

for f in bin/fivebar lib/cmake/fivebar/fivebarConfig.cmake lib/cmake/fivebar/fivebarConfigVersion.cmake \
         lib/cmake/fivebar/fivebarTargets.cmake lib/cmake/fivebar/fivebarCoreTargets.cmake \
         include/fivebar/kinematics.hpp share/fivebar/scad/fivebar.scad share/fivebar/schemas/fk.schema.json \
         share/fivebar/designs/iros2022.yaml share/fivebar/designs/iros2022-index.yaml \
         share/bash-completion/completions/fivebar share/zsh/vendor-completions/_fivebar share/man/man1/fivebar.1; do
  [[ -e $p/$f ]] || fail "$f is not installed"
done
for f in "$src"/docs/*.md; do
  [[ -e $p/share/fivebar/docs/${f##*/} ]] || fail "share/fivebar/docs/${f##*/} is not installed"
done
for f in "$src"/LICENSE "$src"/CITATION.cff "$src"/*.md; do
  [[ -e $p/share/doc/fivebar/${f##*/} ]] || fail "share/doc/fivebar/${f##*/} is not installed"
done
for cmd in $(sed -n 's/^FIVEBAR_COMMAND(\([a-z_]*\)).*/\1/p' "$src/cli/commands.def"); do
  [[ -e $p/share/man/man1/fivebar-$cmd.1 ]] || fail "no man page fivebar-$cmd.1"
done
echo "files: ok"

# No path of the checkout or of the build tree in the installed binary.
for dir in "$src" "$build"; do
  if grep -a -q -F "$dir" "$p/bin/fivebar"; then fail "bin/fivebar holds the path $dir"; fi
done
echo "no checkout path: ok"

# The OpenSCAD library found beside the binary, from a directory with no scad/ of its own.
mkdir -p "$scratch/elsewhere"
cd "$scratch/elsewhere"
env -u FIVEBAR_SCAD_DIR "$p/bin/fivebar" parts "$p/share/fivebar/designs/iros2022.yaml" --no-render --out parts \
  > parts.log 2>&1 || { cat parts.log >&2; fail "parts --no-render with the installed library"; }
[[ -n $(find parts -name fivebar.scad) ]] || fail "parts wrote no copy of fivebar.scad"
mv "$p/share/fivebar/scad" "$scratch/scad-away"
if env -u FIVEBAR_SCAD_DIR "$p/bin/fivebar" parts "$p/share/fivebar/designs/iros2022.yaml" --no-render --out parts2 \
     > parts2.log 2>&1; then
  fail "parts succeeded without share/fivebar/scad: a library path is compiled in"
fi
FIVEBAR_SCAD_DIR="$scratch/scad-away" "$p/bin/fivebar" parts "$p/share/fivebar/designs/iros2022.yaml" --no-render \
  --out parts3 > parts3.log 2>&1 || { cat parts3.log >&2; fail "FIVEBAR_SCAD_DIR no longer overrides"; }
mv "$scratch/scad-away" "$p/share/fivebar/scad"
echo "scad beside the binary: ok"

# Consumers: only find_package(fivebar COMPONENTS ...) and the moved prefix.
generator=()
command -v ninja > /dev/null && generator=(-G Ninja)
for components in "core" "runtime" "core;runtime;full"; do
  name=${components//;/-}
  cmake -S "$src/test/install/consumer" -B "$scratch/consumer-$name" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
        -DCMAKE_PREFIX_PATH="$p" "-DFIVEBAR_CONSUMER_COMPONENTS=$components" > "$scratch/consumer-$name.log" 2>&1 \
    || { cat "$scratch/consumer-$name.log" >&2; fail "consumer ($components) does not configure"; }
  cmake --build "$scratch/consumer-$name" -j 2 >> "$scratch/consumer-$name.log" 2>&1 \
    || { tail -50 "$scratch/consumer-$name.log" >&2; fail "consumer ($components) does not build"; }
  for exe in core_consumer runtime_consumer full_consumer; do
    [[ -x $scratch/consumer-$name/$exe ]] || continue
    "$scratch/consumer-$name/$exe" "$scratch" || fail "$exe ($components) failed"
  done
done
cmake -S "$src/test/install/consumer" -B "$scratch/consumer-bad" "${generator[@]}" -DCMAKE_PREFIX_PATH="$p" \
      "-DFIVEBAR_CONSUMER_COMPONENTS=gui" > "$scratch/consumer-bad.log" 2>&1 && fail "an unknown component was found"
grep -q "no component 'gui'" "$scratch/consumer-bad.log" || { cat "$scratch/consumer-bad.log" >&2; fail "unknown component: no message"; }
grep -q "PACKAGE_VERSION \"$version\"" "$p/lib/cmake/fivebar/fivebarConfigVersion.cmake" || fail "version file is not $version"
echo "consumers: ok"

# Completion: subcommands and options complete; report's own subcommands too.
complete_words() {
  bash -c 'source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); _fivebar; printf "%s\n" "${COMPREPLY[@]}"' \
    _ "$p/share/bash-completion/completions/fivebar" "$@"
}
# (grep reads to the end: with -q it would stop at the first match and, under pipefail, the
# writer killed by SIGPIPE would fail the pipeline whenever it had more lines to write.)
complete_words fivebar rep | grep -x report > /dev/null || fail "bash: 'fivebar rep' does not complete to report"
complete_words fivebar report acc | grep -x accuracy > /dev/null || fail "bash: 'fivebar report acc' does not complete to accuracy"
complete_words fivebar fk designs/x.yaml --the | grep -x -- --theta-file > /dev/null || fail "bash: 'fivebar fk --the' lacks --theta-file"
complete_words fivebar help ik | grep -x ik > /dev/null || fail "bash: 'fivebar help ik' does not complete"
if command -v zsh > /dev/null; then
  zsh -n "$p/share/zsh/vendor-completions/_fivebar" || fail "zsh completion does not parse"
fi
if command -v man > /dev/null; then
  MANWIDTH=100 man -l "$p/share/man/man1/fivebar-fk.1" 2> "$scratch/man.err" | grep -- "--theta-file" > /dev/null \
    || { cat "$scratch/man.err" >&2; fail "man page fivebar-fk.1 does not render --theta-file"; }
fi
echo "completion and man pages: ok"
echo "check_install: all checks passed"
