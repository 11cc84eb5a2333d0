#!/usr/bin/env bash
# A fuzz campaign anyone can repeat: every target in fuzz_targets/ for SECONDS each, JOBS at a
# time, then one line per target with its executions, coverage, corpus and crashes.
#
#   fuzz/campaign.sh [SECONDS_PER_TARGET [JOBS [TARGET...]]]   (defaults: 600 s, 2 at a time, all)
#   SANITIZER=none fuzz/campaign.sh 60                 (no AddressSanitizer: faster, finds less)
#
# Needs cargo-fuzz (installed here with `cargo install cargo-fuzz` when missing). The
# AddressSanitizer build takes nightly-only flags; RUSTC_BOOTSTRAP=1 lets the stable toolchain
# accept them, so no nightly toolchain is needed.
#
# New inputs go to target/campaign/corpus/<target>/ (the committed corpus/ is only read; run
# `cargo fuzz cmin` to fold finds into it). Crash reproducers go to
# target/campaign/artifacts/<target>/: copy each to regressions/<target>/ under a name that
# says what it triggers, and `cargo test` replays it from then on (tests/fuzz_corpus.rs and
# friends).
set -euo pipefail

seconds=${1:-600}
parallel=${2:-2}
shift $(($# < 2 ? $# : 2))
sanitizer=${SANITIZER:-address}
here=$(cd "$(dirname "$0")" && pwd)
cd "$here"

if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "cargo-fuzz is missing; installing it with cargo install cargo-fuzz" >&2
    cargo install cargo-fuzz --locked
fi
export RUSTC_BOOTSTRAP=1

if (($# > 0)); then
    targets=("$@")
else
    mapfile -t targets < <(cargo fuzz list)
fi
echo "building ${#targets[@]} targets (sanitizer: $sanitizer)" >&2
cargo fuzz build -s "$sanitizer" -O >&2
triple=$(rustc -vV | sed -n 's/^host: //p')
bin_dir="$here/target/$triple/release"
out="$here/target/campaign"
mkdir -p "$out"

# Seeds besides the committed corpus (the .pyr reader starts from the golden files).
extra_seeds() {
    if [[ $1 == read_pyr && -d ../formats/golden ]]; then
        echo ../formats/golden
    fi
}

run_target() {
    local t=$1
    mkdir -p "$out/corpus/$t" "$out/artifacts/$t" "corpus/$t"
    # shellcheck disable=SC2046
    "$bin_dir/$t" "$out/corpus/$t" "corpus/$t" $(extra_seeds "$t") \
        -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
        -artifact_prefix="$out/artifacts/$t/" >"$out/$t.log" 2>&1 || true
}

echo "running each target for $seconds s, $parallel at a time; logs in $out" >&2
for t in "${targets[@]}"; do
    while (($(jobs -rp | wc -l) >= parallel)); do
        wait -n || true
    done
    run_target "$t" &
done
wait

# libFuzzer's progress lines read "#RUNS ... cov: C ft: F corp: N/SIZE ..."; its final
# statistics give the executions.
printf '%-12s %12s %8s %8s %10s %8s\n' target executions cov ft corpus crashes
for t in "${targets[@]}"; do
    log="$out/$t.log"
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    last=$(grep -E '^#[0-9]+.*cov: ' "$log" | tail -1 || true)
    cov=$(sed -n 's/.*cov: \([0-9]*\).*/\1/p' <<<"$last")
    ft=$(sed -n 's/.*ft: \([0-9]*\).*/\1/p' <<<"$last")
    corp=$(sed -n 's/.*corp: \([0-9]*\).*/\1/p' <<<"$last")
    crashes=$(find "$out/artifacts/$t" -type f | wc -l)
    printf '%-12s %12s %8s %8s %10s %8s\n' "$t" "${runs:-?}" "${cov:-?}" "${ft:-?}" "${corp:-?}" "$crashes"
done
if find "$out/artifacts" -type f | grep -q .; then
    echo "crash reproducers (copy each to regressions/<target>/ with a descriptive name):"
    find "$out/artifacts" -type f
    exit 1
fi
