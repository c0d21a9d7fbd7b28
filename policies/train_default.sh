#!/bin/bash
# The default policy from scratch (specialists, consolidation, export, evaluation), resumable:
# the same as `ernest train-default`; settings in policies/default.yaml, results in runs/default.
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"  # after ./run setup
exec ernest train-default "$@"
