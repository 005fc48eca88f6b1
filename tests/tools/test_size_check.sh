#!/bin/sh
# tools/fp-size-check lists a file over 1,200 lines and a function over 150 (signature to
# closing brace), and not a function of 150 or a brace block inside one; it always exits 0.
set -eu
tmp=$(mktemp -d /tmp/fp-size-XXXXXX)
trap 'rm -rf "$tmp"' EXIT
{
  printf 'static int long_one(int x)\n{\n'
  i=0; while [ $i -lt 148 ]; do printf '    x += %d; /* { */\n' $i; i=$((i + 1)); done
  printf '}\n\nstatic int just_150(int x)\n{\n    if (x) {\n'
  i=0; while [ $i -lt 144 ]; do printf '        x++;\n'; i=$((i + 1)); done
  printf '    }\n    return "}"[0] + x;\n}\n'
  i=0; while [ $i -lt 900 ]; do printf '/* filler */\n'; i=$((i + 1)); done
} > "$tmp/sample.c"
out=$(tools/fp-size-check "$tmp")
echo "$out"
echo "$out" | grep -q "sample.c: 1202 lines (file over 1200)"
echo "$out" | grep -q "sample.c:1: long_one(): 151 lines (function over 150)"
! echo "$out" | grep -q "just_150"
echo "$out" | grep -q "^fp-size-check: 1 files over 1200 lines, 1 functions over 150 lines"
