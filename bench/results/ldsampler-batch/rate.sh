#!/bin/bash
# Alternates two ldsampler.so builds (/tmp/ld-old/ldsampler.so, /tmp/ld-new/ldsampler.so: copy
# them there first) in the build tree and runs femto bench on the Cornell box of
# ray-rate-path.xml, 5 rounds at 1 and 2 threads, into /tmp/ab/rate/BUILD-tTHREADS-rROUND.
# rate_ratio.py /tmp/ab/rate then gives the table of bench/README.md.
cd "$(dirname "$0")/../../.."   # the repository
# ray-rate-path.xml's Cornell box alone (the mesh is not needed for this comparison)
sed -e '/displaced-sphere/d' bench/experiments/ray-rate-path.xml > bench/experiments/.tmp-box-rate.xml
for t in 1 2; do mkdir -p /tmp/ab/rate
for r in 1 2 3 4 5; do for v in old new; do
  cp /tmp/ld-$v/ldsampler.so build/plugins/ldsampler.so
  ./build/bin/femto bench bench/experiments/.tmp-box-rate.xml --threads $t -o /tmp/ab/rate/$v-t$t-r$r > /tmp/ab/rate/$v-t$t-r$r.log 2>&1
done; done; done
cp /tmp/ld-new/ldsampler.so build/plugins/ldsampler.so
rm -f bench/experiments/.tmp-box-rate.xml
echo DONE
