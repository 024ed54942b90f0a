#!/bin/bash
# cold tmpnav plan, the codes taking turns (benchmarks/README.md, "The localiser's model against the plan time"): base55 = 879ecd6 (a worktree at /tmp/w55: git worktree add /tmp/w55 879ecd6), main = this code as shipped (the beam model), main_amcl = this code with localiser: {model: amcl}
out=/work/main/benchmarks/amcl/plan_time.txt
(cd /work/main && .venv/bin/python -c "
import sys; sys.path.insert(0, 'benchmarks')
from pathlib import Path
from bench_amcl_scenarios import amcl_copy
amcl_copy(Path('configs/building-20.yaml'), Path('/tmp/b20amcl.yaml'))
amcl_copy(Path('configs/building-4robots.yaml'), Path('/tmp/b4amcl.yaml'))")
echo "# cold tmpnav plan (a fresh --cache-dir each run), the codes taking turns; $(date -u '+%Y-%m-%d %H:%M') UTC, $(nproc) cores" > $out
echo "# base55: 879ecd6 (when issue 55 was filed); main: $(cd /work/main && git rev-parse --short HEAD), the shipped configs (the beam model); main_amcl: the same code, localiser: {model: amcl}" >> $out
echo "# label wall_s | tmpnav's total | 1-minute load before the run" >> $out
for round in 1 2 3; do
  for cfg in building-4robots building-20; do
    for code in base55 main main_amcl; do
      case $code in
        base55) dir=/tmp/w55; scen=/tmp/w55/configs/$cfg.yaml;;
        main) dir=/work/main; scen=/work/main/configs/$cfg.yaml;;
        main_amcl) dir=/work/main; if [ $cfg = building-20 ]; then scen=/tmp/b20amcl.yaml; else scen=/tmp/b4amcl.yaml; fi;;
      esac
      rm -rf /tmp/pt_cache /tmp/pt_out
      load=$(cut -d' ' -f1 /proc/loadavg)
      start=$(date +%s.%N)
      (cd $dir && PYTHONPATH=$dir /work/main/.venv/bin/python -m tmpnav plan $scen --cache-dir /tmp/pt_cache -o /tmp/pt_out > /tmp/pt.log 2>&1)
      end=$(date +%s.%N)
      total=$(grep -A1 "^time \[s\]" /tmp/pt.log | tail -1 | awk '{print $(NF-1)}')
      echo "${code}_${cfg} $(echo "$end - $start" | bc | xargs printf '%.2f') | $total | load $load" >> $out
    done
  done
done
