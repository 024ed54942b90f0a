out=/work/main/benchmarks/edits/plan_time.txt
echo "# cold tmpnav plan (a fresh --cache-dir each run), the codes taking turns; $(date -u '+%Y-%m-%d %H:%M') UTC, $(nproc) cores" > $out
echo "# base55: 879ecd6 (when issue 55 was filed), its own configs; main: $(cd /work/main && git rev-parse --short HEAD), the shipped configs (the AMCL model)" >> $out
echo "# label wall_s | tmpnav's total | objective | 1-minute load before the run" >> $out
for round in 1 2 3; do
  for cfg in building-4robots building-20; do
    for code in base55 main; do
      case $code in base55) dir=/tmp/w55;; main) dir=/work/main;; esac
      rm -rf /tmp/pt_cache /tmp/pt_out
      load=$(cut -d' ' -f1 /proc/loadavg)
      start=$(date +%s.%N)
      (cd $dir && PYTHONPATH=$dir /work/main/.venv/bin/python -m tmpnav plan $dir/configs/$cfg.yaml --cache-dir /tmp/pt_cache -o /tmp/pt_out > /tmp/pt.log 2>&1)
      end=$(date +%s.%N)
      total=$(grep -A1 "^time \[s\]" /tmp/pt.log | tail -1 | awk '{print $(NF-1)}')
      obj=$(grep -oE "objective [a-z]+ \([^)]*\): [0-9.]+" /tmp/pt.log | head -1 | grep -oE "[0-9.]+$")
      echo "${code}_${cfg} $(echo "$end - $start" | bc | xargs printf '%.2f') | $total | $obj | load $load" >> $out
    done
  done
done
