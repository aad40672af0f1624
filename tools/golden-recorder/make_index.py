#!/usr/bin/env python3
"""index.json for a folder of episodes (same fields as the published index)."""
import gzip, hashlib, json, os, sys
d = sys.argv[1]
files = []
for n in sorted(os.listdir(d)):
    if not n.endswith('.json.gz'):
        continue
    p = os.path.join(d, n)
    h = json.load(gzip.open(p))['header']
    files.append({"file": n, "config": h["config_name"], "seed": h["seed"], "outcome": h["outcome"],
                  "steps": h["num_steps"], "steps_with_events": h["num_event_steps"],
                  "sha256": hashlib.sha256(open(p, 'rb').read()).hexdigest()})
json.dump({"files": files}, open(os.path.join(d, 'index.json'), 'w'), indent=1)
print(len(files), 'files indexed')
