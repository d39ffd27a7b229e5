#!/bin/sh
# Cell-like load recorded through DDS: publisher process + recorder, RSS sampled every 5 s.
# Usage (inside the isolated namespace): tests/isolated sh nodes/recorder/bench_cell_load.sh SECONDS BINDIR
set -e
S=${1:-60}; BIN=${2:-target/release}; OUT=/tmp/bench_cell_bag_$$
$BIN/metrocell-recorder --ros-args -p output:=$OUT -p compression:=zstd $REC_ARGS &
REC=$!
sleep 1
$BIN/examples/cell_load_publisher --seconds $S &
PUB=$!
T=0
while kill -0 $PUB 2>/dev/null; do
  echo "t=${T}s recorder RSS $(grep VmRSS /proc/$REC/status | awk '{print $2}') kB"
  sleep 5; T=$((T+5))
done
wait $PUB || true
sleep 1
kill -INT $REC; wait $REC || true
$BIN/metrocell bag info $OUT 2>/dev/null || true
du -sh $OUT; rm -rf $OUT
