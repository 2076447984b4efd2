# A sphere against a frictionless side wall of spreading_case.py with DMT adhesion on, side walls
# adhesive or not (scene.side_walls_adhesive, issue 64): the sphere is pressed against the wall (a
# box whose face is the plane y = 0), then pulled away slowly along +y; the largest attraction is
# the pull-off (the contact forms as the sphere approaches, as in the scene). The non-adhesive walls run the template's own unstick_side_walls (read from
# spreading_case.py's text), right after the contact law, as the scene does. Three scenes in one run:
# adhesive walls, non-adhesive walls, and a dry contact (gamma 0) whose first step's force the
# non-adhesive one must equal.
#
#   yade -n -x check_side_wall.py OUT.json GAMMA RADIUS DENSITY YOUNG POISSON
import ast
import json
import math
import os
import sys

from yade import O, utils
from yade import (Bo1_Box_Aabb, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Box_Sphere_ScGeom,
                  Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                  Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin, NewtonIntegrator, PyRunner)

TEMPLATE = os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), "spreading_case.py")
with open(TEMPLATE) as fh:
    _tree = ast.parse(fh.read())
_unstick = [n for n in _tree.body if isinstance(n, ast.FunctionDef) and n.name == "unstick_side_walls"]
exec(compile(ast.Module(body=_unstick, type_ignores=[]), TEMPLATE, "exec"))  # defines unstick_side_walls

out = sys.argv[1]
gamma, R, density, young, poisson = (float(a) for a in sys.argv[2:7])
side_wall_ids = []


def run(gamma, adhesive_walls):
    """Press, then pull: (force on the sphere along +y in the contact's first step, the contact's
    adhesionForce after it, the largest attraction towards the wall, separated at the end)."""
    global side_wall_ids
    O.reset()
    powder = FrictMat(young=young, poisson=poisson, density=density, frictionAngle=math.atan(0.3))
    smooth = FrictMat(young=young, poisson=poisson, density=density, frictionAngle=0.0)
    O.materials.append(powder)
    O.materials.append(smooth)
    shear = young / (2 * (1 + poisson))
    O.dt = 0.05 * math.pi * R * math.sqrt(density / shear) / (0.1631 * poisson + 0.8766)
    wall = O.bodies.append(utils.box((0, -R, 0), (4 * R, R, 4 * R), fixed=True, material=smooth))
    overlap0 = 1e-3 * R
    sphere = O.bodies.append(utils.sphere((0, R - overlap0, 0), R, fixed=True, material=powder))
    side_wall_ids = [wall]
    ip2 = Ip2_FrictMat_FrictMat_MindlinPhys(en=0.4, es=0.4)
    law = Law2_ScGeom_MindlinPhys_Mindlin()
    if gamma > 0.0:
        ip2.gamma = gamma
        law.includeAdhesion = True
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Box_Sphere_ScGeom()], [ip2], [law])] + (
        [PyRunner(command="unstick_side_walls()", iterPeriod=1, initRun=True)]
        if gamma > 0.0 and not adhesive_walls else []) + [NewtonIntegrator(gravity=(0, 0, 0), damping=0.0)]
    O.bodies[sphere].state.vel = (0, -overlap0 / 40.0 / O.dt, 0)  # approaching: the viscous force acts
    O.step()  # the contact forms
    first_force = O.forces.f(sphere)[1]
    adhesion_force = O.interactions[wall, sphere].phys.adhesionForce
    step = overlap0 / 4000.0  # the pull: the overlap released in 4000 steps
    O.bodies[sphere].state.vel = (0, step / O.dt, 0)
    attraction = 0.0
    for _ in range(8000):
        O.step()
        if O.interactions.countReal() == 0:
            break
        attraction = max(attraction, -O.forces.f(sphere)[1])  # force on the sphere towards the wall (-y)
    return {"first_force": first_force, "adhesion_force": adhesion_force, "pull_off": attraction,
            "separated": O.interactions.countReal() == 0}


result = {"gamma": gamma, "radius": R, "adhesive": run(gamma, True), "non_adhesive": run(gamma, False),
          "dry": run(0.0, True)}
with open(out, "w") as fh:
    json.dump(result, fh)
