#!/usr/bin/env bash
# `facepuppet info FILE` on every file of tests/mesh/hostile/: each must be refused with an
# exit code in 1..123, within 10 s, under 2 GiB of virtual memory, with a message naming
# the file; loads-* files (fuzz findings that are valid meshes) must load (exit 0). Usage: hostile-info.sh PATH/TO/facepuppet (run from the repository root).
set -u
exe=$1
asan=0
ldd "$exe" 2>/dev/null | grep -q libasan && asan=1
fail=0
n=0
for f in tests/mesh/hostile/*; do
  n=$((n + 1))
  start=$(date +%s%N)
  if (( asan )); then
    # ASan reserves terabytes of shadow address space: bound its heap instead of ulimit -v
    msg=$(ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}hard_rss_limit_mb=2048:max_allocation_size_mb=2048:allocator_may_return_null=1" \
          timeout 10 "$exe" info "$f" 2>&1 >/dev/null)
  else
    msg=$( (ulimit -v 2097152; timeout 10 "$exe" info "$f") 2>&1 >/dev/null)
  fi
  rc=$?
  ms=$(( ($(date +%s%N) - start) / 1000000 ))
  if [[ $(basename "$f") == loads-* ]]; then
    if (( rc != 0 )); then echo "FAIL $f: exit $rc: $msg"; fail=1; else echo "ok   $f: loads"; fi
  elif (( rc < 1 || rc > 123 )) || [[ $msg != *"$f"* ]]; then
    echo "FAIL $f: exit $rc after ${ms} ms: $msg"
    fail=1
  else
    echo "ok   $f: exit $rc in ${ms} ms"
  fi
done
echo "$n hostile files"
exit $fail
