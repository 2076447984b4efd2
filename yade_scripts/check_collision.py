# Two-body collision with the contact model of spreading_case.py (Hertz-Mindlin, restitution-based
# viscous damping via Ip2 en/es): measures the coefficient of restitution and the contact time.
#
#   yade -n -x check_collision.py OUT.json MODE RESTITUTION SPEED RADIUS DENSITY YOUNG POISSON
#   MODE: "pair" (two equal free spheres, head-on) or "wall" (a sphere on a fixed box, as the floor)
import json
import math
import sys

from yade import O, utils
from yade import (Bo1_Box_Aabb, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Box_Sphere_ScGeom,
                  Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                  Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin, NewtonIntegrator)

out, mode = sys.argv[1], sys.argv[2]
e, v0, R, density, young, poisson = (float(a) for a in sys.argv[3:9])
O.materials.append(FrictMat(young=young, poisson=poisson, density=density, frictionAngle=0.3))
a = O.bodies.append(utils.sphere((0, 0, 0), R))
if mode == "wall":
    b = O.bodies.append(utils.box((0, 0, -2.1 * R), (4 * R, 4 * R, R), fixed=True))
    O.bodies[a].state.vel = (0, 0, -v0)
else:
    b = O.bodies.append(utils.sphere((0, 0, 2.1 * R), R))
    O.bodies[a].state.vel = (0, 0, 0.5 * v0)
    O.bodies[b].state.vel = (0, 0, -0.5 * v0)
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Box_Sphere_ScGeom()],
                             [Ip2_FrictMat_FrictMat_MindlinPhys(en=e, es=e)], [Law2_ScGeom_MindlinPhys_Mindlin()]),
             NewtonIntegrator(gravity=(0, 0, 0), damping=0.0)]
shear = young / (2 * (1 + poisson))
O.dt = 0.01 * math.pi * R * math.sqrt(density / shear) / (0.1631 * poisson + 0.8766)
t_in = t_out = None
for _ in range(500000):
    O.step()
    touching = O.interactions.countReal() > 0
    if touching and t_in is None:
        t_in = O.time
    if t_in is not None and not touching:
        t_out = O.time
        break


def vz(i):
    return O.bodies[i].state.vel[2]


approach = v0  # closing speed before the impact
separation = vz(a) if mode == "wall" else vz(b) - vz(a)  # opening speed after it
with open(out, "w") as fh:
    json.dump({"mode": mode, "restitution_input": e, "impact_speed": v0, "radius": R,
               "restitution_measured": separation / approach,
               "contact_time": (t_out - t_in) if t_out else None, "time_step": O.dt}, fh)
