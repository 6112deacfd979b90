#!/usr/bin/env bash
# Regenerates BENCHMARKS.md (current renderer timings, wavefront vs recursive, ray throughput
# against the peers; optionally end-to-end against Mitsuba 3). The work is in benchmarks.py
# (Python 3 standard library only); `tools/benchmarks.sh --help` lists the options.
#
#   tools/benchmarks.sh                                   # renders + peers, about 10 min on 2 cores
#   tools/benchmarks.sh --quick                           # a quick look, a few minutes
#   tools/benchmarks.sh --bin /path/to/wavepath --parts renders,peers,e2e
set -euo pipefail
exec python3 "$(dirname "${BASH_SOURCE[0]}")/benchmarks.py" "$@"
