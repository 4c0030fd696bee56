#!/usr/bin/env bash
# The bad-input corpus (tests/data/bad/MANIFEST.tsv) under AddressSanitizer,
# UndefinedBehaviorSanitizer and LeakSanitizer: the `rotacal` of the sanitizer build that
# scripts/fuzz.sh configures (build-fuzz/, clang, the same flags; only the command-line program
# is added to it) runs every file twice, as tests/cli/bad_corpus_test.sh checks it. A sanitizer
# report is a second line on stderr and a non-zero exit: the corpus test fails on it.
#   scripts/sanitize-corpus.sh [FILTER]        (FILTER: a substring of the corpus' file names)
# Run after scripts/fuzz.sh (which configures build-fuzz); alone it configures it the same way.
set -euo pipefail
cd "$(dirname "$0")/.."
B=$PWD/build-fuzz
if [ ! -f "$B/CMakeCache.txt" ]; then
  # The sanitizer build without the harnesses: scripts/fuzz.sh's configuration.
  bash scripts/fuzz.sh --configure-only
fi
cmake --build "$B" --target rotacal -j"$(nproc)"
# exitcode 23: a sanitizer report can never pass as the corpus' expected exit 1 or 2.
export ASAN_OPTIONS=detect_leaks=1:exitcode=23
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:exitcode=23
export LSAN_OPTIONS=exitcode=23
start=$(date +%s)
bash tests/cli/bad_corpus_test.sh "$B/cli/rotacal" tests/data/bad/MANIFEST.tsv "${1:-}"
echo "sanitize-corpus: the corpus under ASan + UBSan + LSan, $(( $(date +%s) - start )) s: no report"
