#!/usr/bin/env bash
# splice_benchmarks, shared by scripts/bench.sh and scripts/cost.sh. Sourced only, from the
# repository's root.

# Replaces the lines between `<!-- bench:NAME -->` and `<!-- /bench:NAME -->` of BENCHMARKS.md
# with the file FILE.
splice_benchmarks() {
    local name=$1 file=$2
    grep -q "^<!-- bench:$name -->\$" BENCHMARKS.md && grep -q "^<!-- /bench:$name -->\$" BENCHMARKS.md || {
        echo "splice_benchmarks: BENCHMARKS.md has no <!-- bench:$name --> ... <!-- /bench:$name --> block" >&2
        return 1
    }
    awk -v begin="<!-- bench:$name -->" -v end="<!-- /bench:$name -->" -v file="$file" '
        $0 == begin { print; while ((getline line < file) > 0) print line; skip = 1; next }
        $0 == end { skip = 0 }
        !skip { print }' BENCHMARKS.md >BENCHMARKS.md.new
    mv BENCHMARKS.md.new BENCHMARKS.md
}

