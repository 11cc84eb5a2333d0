#!/usr/bin/env bash
# usage: pyr_open.sh BEFORE_BIN AFTER_BIN MESH [WORKDIR]
# Builds MESH's .pyr file with each binary (printing the sizes by section), then times, three
# times alternating, the whole of `spectrum F.pyr` and `filter F.pyr --lowpass 500` with each
# binary on its own file (open-to-spectrum, open-to-first-filter), and prints what each says
# about the path it took. docs/performance.md ("Stored details") has the figures.
set -u
B=$1; N=$2; m=$3; W=${4:-$(mktemp -d)}
$B build "$m" -o "$W/before.pyr" 2>&1 | sed 's/^/before: /'
$N build "$m" -o "$W/after.pyr" 2>&1 | sed 's/^/after: /'
t() { local s e; s=$(date +%s.%N); "$@" >/dev/null 2>&1; e=$(date +%s.%N); echo "$e - $s" | bc; }
for _ in 1 2 3; do
  echo "spectrum before $(t "$B" -q spectrum "$W/before.pyr" -o "$W/s.png")"
  echo "spectrum after $(t "$N" -q spectrum "$W/after.pyr" -o "$W/s.png")"
  echo "filter before $(t "$B" -q filter "$W/before.pyr" -o "$W/f.ply" --lowpass 500)"
  echo "filter after $(t "$N" -q filter "$W/after.pyr" -o "$W/f.ply" --lowpass 500)"
done
"$N" spectrum "$W/after.pyr" -o "$W/s.png" 2>&1 | head -1 | sed 's/^/after says: /'
"$N" filter "$W/after.pyr" -o "$W/f.ply" --lowpass 500 2>&1 | head -1 | sed 's/^/after says: /'
"$B" filter "$W/before.pyr" -o "$W/f.ply" --lowpass 500 2>&1 | head -1 | sed 's/^/before says: /'
