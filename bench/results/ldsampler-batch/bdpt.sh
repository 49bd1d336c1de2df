#!/bin/bash
# A/B of ldsampler builds on issue 11's box: BDPT and path rays/s, 2 threads.
#     bdpt.sh ROUNDS "old new"   with /tmp/ld-old.so and /tmp/ld-new.so the two plugins
cd "$(dirname "$0")/../../.."   # the repository
source bench/common.sh
steady_scene_with transient_bdpt scenes/cornell-box/scene.xml > scenes/cornell-box/.ab-bdpt.xml
steady_scene_with transient_path scenes/cornell-box/scene.xml > scenes/cornell-box/.ab-path.xml
echo "round,build,integrator,seconds,mrays"
for r in $(seq 1 $1); do for v in $2; do
  cp /tmp/ld-$v.so build/plugins/ldsampler.so
  for i in bdpt path; do
    out=$(./build/bin/femto render scenes/cornell-box/.ab-$i.xml -D res=64 --spp 256 --threads 2 -o /tmp/ab/x 2>&1 | render_seconds_and_rate)
    echo "$r,$v,$i,${out// /,}"
  done
done; done
cp /tmp/ld-new.so build/plugins/ldsampler.so
rm -f scenes/cornell-box/.ab-*.xml
