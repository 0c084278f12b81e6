#!/usr/bin/env bash
# Bounded coverage-guided fuzzing of the frame scanner, the matcher, the
# text parsers (connection strings, `sim:` queries, durations, allow
# patterns) and the HTTP server of `mavping serve` and `--prometheus`.
#   scripts/fuzz.sh [SECONDS] [TARGET...]   (default 60 s per target; all targets)
# Needs cargo-fuzz (`cargo install cargo-fuzz`) and a nightly toolchain, or
# the stable one with RUSTC_BOOTSTRAP=1 (set here when no nightly exists).
# The committed seeds (fuzz/seeds/<target>: real v1, v2 and signed frames
# made by pymavlink, fuzz/seed_corpus.py; connection strings and requests
# written by hand) are read only. What the fuzzer learns goes to
# fuzz/corpus/<target> (ignored by git), which starts from the minimised
# corpus of the 30-minute runs (fuzz/corpora/<target>.tar.gz) when empty.
# A crash leaves its input in fuzz/artifacts/<target> and makes this script
# exit non-zero.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
SECONDS_PER_TARGET=${1:-60}
shift || true
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(scanner matcher parse http)

if rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
  CARGO=(cargo +nightly)
else
  export RUSTC_BOOTSTRAP=1
  CARGO=(cargo)
fi
"${CARGO[@]}" fuzz build -O

for target in "${TARGETS[@]}"; do
  mkdir -p "corpus/$target"
  if [ -f "corpora/$target.tar.gz" ] && [ -z "$(ls -A "corpus/$target")" ]; then
    tar -xzf "corpora/$target.tar.gz" -C "corpus/$target"
  fi
  echo "== $target: ${SECONDS_PER_TARGET}s"
  set +e
  "${CARGO[@]}" fuzz run -O "$target" "corpus/$target" "seeds/$target" -- \
    -max_total_time="$SECONDS_PER_TARGET" -timeout=10 -print_final_stats=1 2>&1 |
    awk '/cov:/ { last = $0 } /^stat::|^INFO: seed corpus|^==[0-9]+==|^SUMMARY|Test unit written|panicked/ { print } END { if (last) print "last status: " last }'
  status=${PIPESTATUS[0]}
  set -e
  if [ "$status" -ne 0 ]; then
    echo "fuzz target $target failed (exit $status); see fuzz/artifacts/$target" >&2
    exit "$status"
  fi
done
