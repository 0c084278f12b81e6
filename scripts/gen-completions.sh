#!/usr/bin/env bash
# Regenerates the committed shell completions and man pages from the clap
# definition. tests/it/completions.rs fails when they are out of date.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --quiet
bin=target/debug/mavping
mkdir -p completions
"$bin" --generate complete-bash > completions/mavping.bash
"$bin" --generate complete-zsh > completions/_mavping
"$bin" --generate complete-fish > completions/mavping.fish
"$bin" --generate complete-powershell > completions/_mavping.ps1
"$bin" --generate complete-elvish > completions/mavping.elv
"$bin" --generate man > completions/mavping.1
"$bin" --generate man-respond > completions/mavping-respond.1
"$bin" --generate man-compare > completions/mavping-compare.1
echo "completions/ regenerated"
