# DMT adhesion of the contact law of spreading_case.py (Hertz-Mindlin with Ip2 `gamma` and Law2
# `includeAdhesion`), measured on two bodies:
#
#   yade -n -x check_adhesion.py OUT.json MODE GAMMA RADIUS DENSITY YOUNG POISSON GRAVITY
#   MODE: "pull" (two equal spheres pressed together, one then pulled away slowly along z: the
#         largest attraction is the pull-off force), "pull_wall" (a sphere pulled off a fixed box),
#         "rest" (a sphere resting on a fixed box under gravity: its static overlap)
import json
import math
import sys

from yade import O, utils
from yade import (Bo1_Box_Aabb, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Box_Sphere_ScGeom,
                  Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                  Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin, NewtonIntegrator)

out, mode = sys.argv[1], sys.argv[2]
gamma, R, density, young, poisson, gravity = (float(a) for a in sys.argv[3:9])
O.materials.append(FrictMat(young=young, poisson=poisson, density=density, frictionAngle=0.3))
shear = young / (2 * (1 + poisson))
O.dt = 0.05 * math.pi * R * math.sqrt(density / shear) / (0.1631 * poisson + 0.8766)
if mode == "rest":
    a = O.bodies.append(utils.box((0, 0, -R), (4 * R, 4 * R, R), fixed=True))
    b = O.bodies.append(utils.sphere((0, 0, 1.001 * R), R))
    restitution, damping, g = 0.4, 0.3, gravity
else:
    overlap0 = 1e-3 * R
    if mode == "pull_wall":
        a = O.bodies.append(utils.box((0, 0, -R), (4 * R, 4 * R, R), fixed=True))
        b = O.bodies.append(utils.sphere((0, 0, R - overlap0), R, fixed=True))
    else:
        a = O.bodies.append(utils.sphere((0, 0, 0), R, fixed=True))
        b = O.bodies.append(utils.sphere((0, 0, 2 * R - overlap0), R, fixed=True))
    restitution, damping, g = 1.0, 0.0, 0.0  # no viscous force: the pull is slow and elastic
law = Law2_ScGeom_MindlinPhys_Mindlin(includeAdhesion=gamma > 0)
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Box_Sphere_ScGeom()],
                             [Ip2_FrictMat_FrictMat_MindlinPhys(en=restitution, es=restitution, gamma=gamma)], [law]),
             NewtonIntegrator(gravity=(0, 0, -g), damping=damping)]
result = {"mode": mode, "gamma": gamma, "radius": R, "density": density, "young": young, "poisson": poisson,
          "gravity": gravity, "time_step": O.dt}
if mode == "rest":
    mass = O.bodies[b].state.mass
    O.run(40000, True)  # ~150 periods of the contact's oscillation: at rest
    i = O.interactions[a, b]
    result.update({"mass": mass, "overlap": i.geom.penetrationDepth, "speed": O.bodies[b].state.vel.norm(),
                   "adhesion_force": i.phys.adhesionForce, "steps": O.iter})
else:
    O.step()  # the contact forms
    adhesion_force = O.interactions[a, b].phys.adhesionForce
    step = overlap0 / 4000.0  # the pull: the overlap released in 4000 steps
    O.bodies[b].state.vel = (0, 0, step / O.dt)
    attraction, last_overlap = 0.0, None
    for _ in range(8000):
        O.step()
        if O.interactions.countReal() == 0:
            break
        attraction = max(attraction, -O.forces.f(b)[2])  # force on b towards a (-z)
        last_overlap = O.interactions[a, b].geom.penetrationDepth
    result.update({"pull_off": attraction, "adhesion_force": adhesion_force, "last_overlap": last_overlap,
                   "separated": O.interactions.countReal() == 0})
with open(out, "w") as fh:
    json.dump(result, fh)
