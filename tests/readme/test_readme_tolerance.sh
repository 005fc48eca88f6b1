#!/bin/bash
# tools/readme-figures' comparison: a figure whose decimals differ from the command's only in
# their last digits (within a relative 1e-4: the engine's SIMD paths round differently)
# matches, and --write leaves it; a count off by one, a decimal off by more, or another word
# drifts (exit 1), and --write then rewrites the block. Uses `echo` figures in a scratch
# README, so it needs no build and no shared data.
set -u
tool="$1/tools/readme-figures"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-readme-tol-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/data/faces" "$tmp/bin"
fail() { echo "FAIL: $*"; exit 1; }

# check README_LINE COMMAND_OUTPUT WANT_EXIT
check() {
    printf '%s\n' "# t" "<!-- fp-figure: echo '$2' -->" '```text' "$1" '```' > "$tmp/README.md"
    python3 "$tool" --check --readme "$tmp/README.md" --bin "$tmp/bin" --data "$tmp/data" > "$tmp/out" 2>&1
    local rc=$?
    [ $rc -eq "$3" ] || { cat "$tmp/out"; fail "'$1' against '$2': exit $rc, want $3"; }
}
have='frames 200; moved 12659; mean 2.2 mm (0.220231, 2.59253 units); followed 25%'
check "$have" "$have" 0
check "$have" 'frames 200; moved 12659; mean 2.2 mm (0.22023, 2.59254 units); followed 25%' 0
check "$have" 'frames 200; moved 12660; mean 2.2 mm (0.220231, 2.59253 units); followed 25%' 1
check "$have" 'frames 200; moved 12659; mean 2.2 mm (0.2203, 2.59253 units); followed 25%' 1
check "$have" 'frames 200; moved 12659; mean 2.3 mm (0.220231, 2.59253 units); followed 25%' 1
check "$have" 'frames 200; moved 12659; mean 2.2 mm (0.220231, 2.59253 units); kept 25%' 1
check "$have" 'frames 200; moved 12659; mean 2.2 mm (0.220231 units); followed 25%' 1

# --write: a block within rounding stays as it is, one that drifted is rewritten
check "$have" 'frames 200; moved 12659; mean 2.2 mm (0.22023, 2.59254 units); followed 25%' 0
cp "$tmp/README.md" "$tmp/before.md"
python3 "$tool" --write --readme "$tmp/README.md" --bin "$tmp/bin" --data "$tmp/data" > /dev/null 2>&1 ||
    fail "--write exited non-zero"
cmp -s "$tmp/README.md" "$tmp/before.md" || fail "--write rewrote a block within rounding"
check "$have" 'frames 200; moved 12660; mean 2.2 mm (0.220231, 2.59253 units); followed 25%' 1
python3 "$tool" --write --readme "$tmp/README.md" --bin "$tmp/bin" --data "$tmp/data" > /dev/null 2>&1 ||
    fail "--write exited non-zero"
grep -q 'moved 12660' "$tmp/README.md" || fail "--write left a drifted block"
echo ok
