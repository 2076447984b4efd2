# Head-on impact of two equal spheres (Hertz-Mindlin, as in spreading_case.py), the overlap read
# every step with YADE's maxOverlapRatio (the scene's stability record): the series lets a test
# sample it at the scene's stride and compare the peak with Hertz theory.
#
#   yade -n -x check_impact_overlap.py OUT.json RESTITUTION SPEED RADIUS DENSITY YOUNG POISSON TIME_STEP
import json
import sys

from yade import O, utils
from yade import (Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider,
                  InteractionLoop, Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin,
                  NewtonIntegrator)
import yade._utils

out = sys.argv[1]
e, v0, R, density, young, poisson, dt = (float(a) for a in sys.argv[2:9])
O.materials.append(FrictMat(young=young, poisson=poisson, density=density, frictionAngle=0.3))
a = O.bodies.append(utils.sphere((0, 0, 0), R))
b = O.bodies.append(utils.sphere((0, 0, 2.0 * R + 2.0 * v0 * dt), R))  # they touch in the second step
O.bodies[a].state.vel = (0, 0, 0.5 * v0)
O.bodies[b].state.vel = (0, 0, -0.5 * v0)
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_MindlinPhys(en=e, es=e)],
                             [Law2_ScGeom_MindlinPhys_Mindlin()]),
             NewtonIntegrator(gravity=(0, 0, 0), damping=0.0)]
O.dt = dt
series, touched = [], False
for _ in range(1000000):
    O.step()
    real = O.interactions.countReal() > 0
    touched = touched or real
    series.append(yade._utils.maxOverlapRatio() if real else 0.0)
    if touched and not real:
        break
with open(out, "w") as fh:
    json.dump({"overlap_ratio_series": series, "time_step": dt, "impact_speed": v0, "radius": R}, fh)
