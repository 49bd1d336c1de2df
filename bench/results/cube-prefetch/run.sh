#!/bin/bash
cd /work/main
for r in 1 2 3; do
  for t in 1 2; do
    order="A B"; (( r % 2 == 0 )) && order="B A"
    for v in $order; do
      p=/work/ab/fn; [[ $v == B ]] && p=/work/ab/pf
      out=/tmp/abpf/$v-t$t-r$r; rm -rf $out
      $p/bin/femto bench bench/experiments/transient-throughput.xml --threads $t -o $out > $out.log 2>&1
    done
  done
done
echo DONE
