#!/usr/bin/env python3
"""Caps a harness's corpus at N inputs, keeping the N that cover the most edges (tests/fuzz/README.md).

`cargo test` gives each harness one second, corpus included: a corpus that takes longer is replayed
only in part. The harnesses that write and read files (bag_recover, csv_import, mcap_files,
launch_plans) take 5-30 ms an input, so their corpora are capped.

    tests/fuzz/cap_corpus.py HARNESS TEST_BINARY N

TEST_BINARY is the libFuzzer build cargo bolero made (target/fuzz/libfuzzer/x86_64-unknown-linux-gnu/
fuzz/deps/binary_formats-* or text_formats-*). The binary merges the corpus with -use_counters=0
(one feature an edge) into a control file; inputs are then picked greedily, each the one adding the
most edges not yet covered. The others are deleted; it prints the edges kept.
"""

import os
import subprocess
import sys
import tempfile

harness, binary, cap = sys.argv[1], os.path.abspath(sys.argv[2]), int(sys.argv[3])
crate = os.path.dirname(os.path.abspath(__file__))
corpus = os.path.join(crate, "tests", "__fuzz__", harness, "corpus")
with tempfile.TemporaryDirectory() as tmp:
    control = os.path.join(tmp, "control")
    os.mkdir(os.path.join(tmp, "merged"))
    env = dict(
        os.environ,
        BOLERO_TEST_NAME=harness,
        BOLERO_LIBTEST_HARNESS="1",
        BOLERO_LIBFUZZER_ARGS=f"-merge=1 -use_counters=0 -merge_control_file={control} "
        f"{os.path.join(tmp, 'merged')} {corpus}",
    )
    args = [binary, harness, "--exact", "--nocapture", "--quiet", "--test-threads", "1"]
    subprocess.run(args, env=env, cwd=crate, check=True, capture_output=True)
    lines = open(control).read().split("\n")

count = int(lines[0])
names = lines[2 : 2 + count]
features, current = {}, None
for line in lines[2 + count :]:
    words = line.split()
    if words and words[0] == "STARTED":
        current = int(words[1])
        features[current] = set()
    elif words and words[0] == "FT":
        features[int(words[1])] |= set(map(int, words[2:]))
every = set().union(*features.values())
kept, covered = [], set()
while len(kept) < cap:
    best = max(features, key=lambda i: len(features[i] - covered))
    if not features[best] - covered:
        break
    kept.append(best)
    covered |= features[best]
keep = {os.path.basename(names[i]) for i in kept}
for name in os.listdir(corpus):
    if name not in keep:
        os.remove(os.path.join(corpus, name))
print(f"{harness}: kept {len(keep)} of {count} inputs, {len(covered)} of {len(every)} edges")
