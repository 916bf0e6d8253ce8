#!/usr/bin/env bash
# Every reproduction config (configs/<paper>_*.toml, e.g. cui2025_table2.toml) run in full (resumable), then its figures into figures/.
#   scripts/reproduce_all.sh            full runs (hours on 2 cores; interrupt and re-run to resume)
#   scripts/reproduce_all.sh --quick    the CI smoke runs
set -euo pipefail
cd "$(dirname "$0")/.."
exec jaxplan reproduce "$@"
