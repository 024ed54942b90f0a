#!/bin/bash
# alternate old/new fresh plans of the shipped configs without the new keys
out=/tmp/bench_same.txt; : > $out
for i in 1 2 3; do
  for v in old new; do
    if [ $v = old ]; then dir=/tmp/old; else dir=/work/main; fi
    for cfg in corridor-2robots building-20; do
      c=$(mktemp -d)
      s=$(date +%s.%N)
      (cd $dir && PYTHONPATH=$dir /work/main/.venv/bin/python -m tmpnav plan configs/$cfg.yaml -q --cache-dir $c -o $c/out > $c/log 2>&1)
      rc=$?
      e=$(date +%s.%N)
      obj=$(python3 -c "import json;d=json.load(open('$c/out/plan.json'));print(round(d['objective']['resimulated'],3))" 2>/dev/null)
      echo "$i $v $cfg rc=$rc $(python3 -c "print(round($e-$s,2))") obj=$obj" >> $out
      rm -rf $c
    done
  done
done
