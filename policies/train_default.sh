#!/bin/bash
# Four quick specialists (two at a time on 2 cores), then consolidation (Table 4) and export.
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"  # after ./run setup
train() {
  ernest train --scenario "$1" --preset quick --steps 30000 --run-dir "runs/$1" \
    --set eval.every_steps=10000 --set eval.episodes=3 \
    --set "eval.baseline={action: [1, 0, 0], kwargs: {passive: true}}" \
    --set checkpoint.every_steps=10000 --set log.progress_bar=false > "runs/$1.log" 2>&1
  echo "$1 exit $?" >> runs/status.txt
}
train step & train slope & wait
train rockfield & train ripples & wait
echo "specialists done $(date)" >> runs/status.txt
ernest consolidate runs/step runs/slope runs/rockfield runs/ripples --out runs/consolidated > runs/consolidate.log 2>&1
echo "consolidate exit $? $(date)" >> runs/status.txt
ernest export runs/consolidated --out policies/ernest_default.pt
ernest evaluate --policy policies/ernest_default.pt --out out/report_learned --no-video
