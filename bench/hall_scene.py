#!/usr/bin/env python3
"""Writes the hall of docs/scale.md's 10^9-voxel run: a 100 x 100 x 12.5 m region at 5 cm
(10^9 voxels), 81 pillars, 16 cameras high on a circle looking across.

    python3 bench/hall_scene.py OUT.json
    build/pandora analyze OUT.json --out out/hall --memory-budget 20000     # 10^9 voxels
    build/pandora analyze OUT.json --out out/hall --voxel-size 0.1          # 1.25 x 10^8
"""
import sys
import json, math
objs=[{"name":"floor","box":{"size":[104,104,0.2]},"position":[0,0,-0.1],"solid":True}]
for i in range(-4,5):
    for j in range(-4,5):
        objs.append({"name":f"pillar_{i}_{j}","box":{"size":[0.6,0.6,12]},"position":[i*11.0,j*11.0,6.0],"solid":True})
cams=[]
for k in range(16):
    a=2*math.pi*k/16
    p=[49*math.cos(a),49*math.sin(a),9.0]
    t=[10*math.cos(a+0.6),10*math.sin(a+0.6),1.0]
    cams.append({"id":f"c{k+1:02d}","position":[round(x,3) for x in p],"look_at":[round(x,3) for x in t],"up":[0,0,1],
                 "resolution":[3840,2160],"hfov_deg":70,"range":{"near":0.5,"far":120}})
scene={"pandora":1,"units":"m","objects":objs,"rigs":[{"name":"hall16","cameras":cams}],
       "study":{"region":{"box":{"min":[-50,-50,0.0],"max":[50,50,12.5]}},"voxel_size":0.05,"fields":["coverage"]}}
json.dump(scene, open(sys.argv[1], "w"), indent=1)
