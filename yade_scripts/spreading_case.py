# One powder-spreading case on YADE (Hertz-Mindlin spheres, a moving recoater blade).
#
# Run by hand:   yade -n -x spreading_case.py [RAW_OUTPUT.json]
# (without an argument the raw result goes to <this script>.raw.json)
#
# Protocol (see SPEC.md of spreadmap):
#   1. settle:  a random loose cloud of spheres (of one size, or of a size distribution: psd_sizes)
#               falls into a box on the floor
#               (temporary walls at x = 0 and x = pile_length), with NewtonIntegrator
#               damping switched on only in this phase;
#   2. relax:   damping off, temporary walls removed, the blade placed with its lower face at
#               height `gap` and its front face at x = 0; run until the kinetic energy decays;
#   3. move:    the blade moves in +x at `blade_speed`; powder extrudes through the gap and is
#               deposited behind it. No artificial damping: only the contact law dissipates;
#   4. measure: snapshots of all spheres when the blade's rear face passes the start and the end
#               of the measurement window (beyond the pile and a transient); then stop.
#
# This script runs under YADE's own (Debian system) Python. It imports nothing from the
# spreadmap venv: it simulates and writes raw results (atomically), nothing more. MFR, PD and
# the regime are computed afterwards by the spreadmap package.
#
# Units: SI throughout (m, s, kg).
import json
import math
import os
import random
import sys
import time

from yade import O, pack, utils
from yade import (Bo1_Box_Aabb, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Box_Sphere_ScGeom,
                  Ig2_Box_Sphere_ScGeom6D, Ig2_Sphere_Sphere_ScGeom, Ig2_Sphere_Sphere_ScGeom6D,
                  InsertionSortCollider, InteractionLoop,
                  Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin,
                  NewtonIntegrator, PyRunner, Sphere)
import yade._utils
import yade.config

# The case's parameters: the keys spreadmap.case.scene.scene_parameters emits (tests/case/test_scene_parts.py).
# Two switches of the benchmarks are read only when given (P.get): `timing` (YADE's engine timers,
# benchmarks/engine_profile.py) and `move_steps_limit` (stop after that many steps of the move).
# --- case parameters (written by spreadmap's renderer; the values below are a demo case) ---
PARAMS = {
    "case_id": "demo",
    "point": {"f": 0.3, "d_um": 40.0, "h_um": 65.0, "v_mm_s": 10.0},
    "preset": "demo",
    "scene_sha256": None,
    "friction": 0.3,
    "diameter": 4e-05,
    "gap": 6.5e-05,
    "blade_speed": 0.01,
    "density": 798000.0,
    "density_scale": 100.0,
    "young": 2.1e9,
    "poisson": 0.3,
    "restitution": 0.4,
    "gravity": 9.81,
    "time_step": 4.0e-07,
    "critical_time_step": 2.13e-06,
    "width": 0.00016,
    "pile_length": 0.00032,
    "pile_height": 0.0003,
    "cloud_height": 0.0006,
    "n_particles": 200,
    "blade_thickness": 8e-05,
    "transient_travel": 0.00016,
    "window_travel": 0.00032,
    "seed": 1,
    "settle_damping": 0.4,
    "ke_tolerance": 0.001,
    "settle_max_time": 0.05,
    "relax_max_time": 0.05,
    "max_speed": 2.0,
    "watchdog_every": 50,
    "control_every": 100,
    "monitor_every": 1000,
    "progress_every_s": 10.0,
    "surface_energy": 0.0,
    "adhesion_gamma": 0.0,
    "size_span": 0.0,
    "psd_sizes": [],
    "psd_cumulative": [],
    "rolling_resistance": False,
    "rolling_friction": 0.0,
    "rolling_stiffness": 0.0,
    "stop_after": None,
    "substrate": "flat",
    "substrate_jitter": 0.5,
    "overlap_every": 1,
    "target_passed": None,
    "window_max_travel": 0.00032,
    "floor_ahead": 40.0,
    "substrate_ahead": 12.0,
    "steady_min_travel": None,
    "steady_span": 8e-05,
    "steady_z": 2.0,
    "counting_noise_c": 0.45,
    "freeze_behind_d": None,
    "freeze_speed_ratio": 0.02,
    "feed_count": None,
    "feed_zone": 0.00012,
    "feed_offset": 0.0,
    "side_walls_adhesive": True,
    "contact_time": 2.0e-06,
    "estimated_steps": 500000,
    "timeout_s": 600.0,
}
# --- end of case parameters ---

P = PARAMS
EXIT_OK, EXIT_REFUSED, EXIT_BLOWN, EXIT_FAILED = 0, 2, 3, 4
out_path = sys.argv[1] if len(sys.argv) > 1 else os.path.splitext(os.path.abspath(sys.argv[0]))[0] + ".raw.json"
wall_start = time.time()


POINT = "f=%.3f d=%.1fum h=%.1fum v=%.2fmm/s" % (P["friction"], P["diameter"] * 1e6, P["gap"] * 1e6,
                                                  P["blade_speed"] * 1e3)


def log(msg):
    print("[%s] %s" % (P["case_id"], msg))
    sys.stdout.flush()


def rayleigh_step(radius, density, young, poisson):
    shear = young / (2.0 * (1.0 + poisson))
    return math.pi * radius * math.sqrt(density / shear) / (0.1631 * poisson + 0.8766)


def write_atomically(path, data):
    tmp = path + ".tmp%d" % os.getpid()
    with open(tmp, "w") as fh:
        json.dump(data, fh, separators=(",", ":"))
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


# ---- refuse an unstable step before anything runs -------------------------------------------
# d is the powder's D50 (one size: its diameter); the size distribution, when given, is sieve sizes
# (diameters) and cumulative volume fractions (spreadmap.case.psd). The critical step is the
# smallest sphere's.
R = 0.5 * P["diameter"]
PSD = bool(P.get("psd_sizes"))
d_min = P["psd_sizes"][0] if PSD else P["diameter"]
d_max = P["psd_sizes"][-1] if PSD else P["diameter"]
dt_crit = rayleigh_step(0.5 * d_min, P["density"], P["young"], P["poisson"])
if P["time_step"] > dt_crit:
    log("REFUSED: time_step %.3e s is above the Rayleigh critical step %.3e s of this case "
        "(smallest sphere d = %.1f um, density %.0f kg/m3); lower it below the critical step." %
        (P["time_step"], dt_crit, d_min * 1e6, P["density"]))
    sys.exit(EXIT_REFUSED)

# ---- geometry ---------------------------------------------------------------------------------
d = P["diameter"]
W = P["width"]
L = P["pile_length"]
h = P["gap"]
tb = P["blade_thickness"]
# Blade rear face positions. The window opens after the blade has swept the pile and a transient
# (transient_travel); with steady_min_travel set, it opens earlier, as soon as the flow under the
# blade is steady (steady_test), transient_travel being then the cap. It lasts window_travel; with a
# target it goes on until target_passed spheres' worth of volume has passed, up to window_max_travel.
x_window_start = L + P["transient_travel"]          # at the latest
adaptive_window = P.get("target_passed") is not None
window_longest = P["window_max_travel"] if adaptive_window else P["window_travel"]
x_window_cap = x_window_start + window_longest      # the farthest the blade can go
x_window_end = x_window_start + P["window_travel"]  # reset when the window opens
x_lo = -tb - 20.0 * d                                # modelled length of the floor
x_hi = x_window_cap + L + P["floor_ahead"] * d
z_hi = P["cloud_height"] + 40.0 * d
sphere_volume = math.pi * d ** 3 / 6.0  # with a size distribution: the placed spheres' mean (below)

O.reset()
O.dt = P["time_step"]
frict = FrictMat(young=P["young"], poisson=P["poisson"], density=P["density"],
                 frictionAngle=math.atan(P["friction"]), label="powder")
smooth = FrictMat(young=P["young"], poisson=P["poisson"], density=P["density"],
                  frictionAngle=0.0, label="frictionless")
O.materials.append(frict)
O.materials.append(smooth)

cx, span = 0.5 * (x_lo + x_hi), 0.5 * (x_hi - x_lo)
# floor (friction f, like the powder) and the two frictionless side walls: boxes whose inner
# faces are at z = 0, y = 0 and y = W.
# Collision masks: the powder (3) meets everything; the rough substrate and the floor under it (6)
# meet the powder but not one another (the collider's avoidSelfInteractionMask 4): fixed bodies
# never interact, and no potential interaction between them costs a step. Blade and walls: 1.
POWDER_MASK, SUBSTRATE_MASK, AVOID_MASK = 3, 6, 4
floor_top = -d if P["substrate"] == "rough" else 0.0   # under a rough substrate, a backstop
# box_ids: the boxes a sphere can press (these, the settle's temporary walls, the blade)
box_ids = [O.bodies.append(utils.box((cx, 0.5 * W, floor_top - d), (span, 0.5 * W + 2 * d, d), fixed=True, material=frict,
                                     mask=SUBSTRATE_MASK if P["substrate"] == "rough" else 1))]
for yc in (-d, W + d):
    box_ids.append(O.bodies.append(utils.box((cx, yc, 0.5 * z_hi), (span, d, 0.5 * z_hi + d), fixed=True, material=smooth)))
side_wall_ids = box_ids[1:3]
# A rough substrate (the previous layer): fixed spheres of the powder's diameter on a hexagonal
# lattice (seeded offset, rows along x), each lowered by a seeded random depth in
# [0, substrate_jitter x R], so that their highest points lie in [-jitter R, 0]: z = 0 is the top of
# the substrate, the reference of the gap h and of every layer metric. The flat floor box stays
# below it (its face at z = -d; a sphere of the powder cannot pass between touching substrate spheres).
# Fixed spheres cost time in every step, so the substrate is laid only as far as the powder
# reaches: to substrate_ahead beyond the pile's far end, and extended in steps of 10 d as the blade
# advances (extend_substrate, from control()); the lattice and its random depths are the same
# whenever they are laid.
x_substrate = -tb - 4.0 * d  # behind the blade's start only what the collapsing pile can reach
substrate = {"positions": [], "radii": [], "rows": [], "x_end": x_substrate, "ids": []}
if P["substrate"] == "rough":
    substrate_rng = random.Random(1000003 * int(P["seed"]) + 17)
    row_pitch = math.sqrt(3.0) * R
    y0 = substrate_rng.uniform(0.0, row_pitch)
    x0 = substrate_rng.uniform(0.0, d)
    for j in range(int(math.ceil((W + 2 * d) / row_pitch)) + 1):
        yc = -d + y0 + j * row_pitch
        if yc > W + R:
            break
        substrate["rows"].append([yc, x_substrate + x0 + (0.5 * d if j % 2 else 0.0)])  # y, next x to lay
elif P["substrate"] != "flat":
    log("REFUSED: substrate %r is neither 'flat' nor 'rough'" % P["substrate"])
    sys.exit(EXIT_REFUSED)


def extend_substrate(x_to):
    """Lay the rough substrate up to x_to (never beyond the floor's end). A sphere of the powder that
    rolled beyond the substrate's end lies on the floor below it, where the next substrate spheres
    go: no substrate sphere is laid within 2 R of one (R + its radius with a size distribution; the
    random depth is drawn all the same, so the layout never depends on where the powder is)."""
    x_to = min(x_to, x_hi)
    while substrate["x_end"] < x_to:
        chunk_end = substrate["x_end"] + 10.0 * d
        reach = 2.0 * d_max if PSD else d
        nearby = [(b.state.pos, b.shape.radius) for b in (O.bodies[i] for i in sphere_ids)
                  if substrate["x_end"] - reach <= b.state.pos[0] <= chunk_end + reach
                  and (b.state.pos[2] - b.shape.radius < 0.0 if PSD else b.state.pos[2] < R)]
        for row in substrate["rows"]:
            while row[1] < chunk_end:
                zc = -R - substrate_rng.uniform(0.0, P["substrate_jitter"] * R)
                centre = (row[1], row[0], zc)
                # (one size: 2 R; a size distribution: R + the powder sphere's radius)
                if not any((p[0] - centre[0]) ** 2 + (p[1] - centre[1]) ** 2 + (p[2] - zc) ** 2
                           < ((R + r) if PSD else 2.0 * R) ** 2 for p, r in nearby):
                    substrate["ids"].append(
                        O.bodies.append(utils.sphere(centre, R, fixed=True, material=frict, mask=SUBSTRATE_MASK)))
                    substrate["positions"].append(list(centre))
                    substrate["radii"].append(R)
                row[1] += d
        substrate["x_end"] = chunk_end


temporary_walls = [
    O.bodies.append(utils.box((xc, 0.5 * W, 0.5 * P["cloud_height"]), (d, 0.5 * W, 0.5 * P["cloud_height"] + d),
                              fixed=True, material=smooth))
    for xc in (-d, L + d)
]
box_ids += temporary_walls

cloud = pack.SpherePack()
if PSD:  # YADE's own placer: sizes by volume fraction (distributeMass), the largest placed first
    placed = cloud.makeCloud((0, 0, 0), (L, W, P["cloud_height"]), psdSizes=list(P["psd_sizes"]),
                             psdCumm=list(P["psd_cumulative"]), distributeMass=True,
                             num=int(P["n_particles"]), seed=int(P["seed"]))
else:
    placed = cloud.makeCloud((0, 0, 0), (L, W, P["cloud_height"]), rMean=R, rRelFuzz=0.0,
                             num=int(P["n_particles"]), seed=int(P["seed"]))
if placed != int(P["n_particles"]):
    log("FAILED: makeCloud placed %d of %d spheres in the cloud box (%.0f um high): the cloud is too dense; "
        "lower the config key scene.cloud_fraction" % (placed, P["n_particles"], P["cloud_height"] * 1e6))
    sys.exit(EXIT_FAILED)
sphere_ids = list(cloud.toSimulation(material=frict))
for i in sphere_ids:
    O.bodies[i].mask = POWDER_MASK
if PSD:
    sphere_volume = sum(4.0 / 3.0 * math.pi * O.bodies[i].shape.radius ** 3 for i in sphere_ids) / len(sphere_ids)
    smallest_mass = min(O.bodies[i].state.mass for i in sphere_ids)
    ke_scale = sum(O.bodies[i].state.mass for i in sphere_ids) * P["gravity"] * d  # lifting every sphere by d
else:
    smallest_mass = P["density"] * sphere_volume
    ke_scale = P["n_particles"] * smallest_mass * P["gravity"] * d  # lifting every sphere by one diameter
# the spheres of the size distribution by number (the fed heap draws from it): each sieve class's
# volume fraction over its mean sphere volume, cumulated
psd_classes = []
if PSD:
    sizes, fractions = P["psd_sizes"], P["psd_cumulative"]
    weights = [(fractions[k + 1] - fractions[k]) / (0.5 * (sizes[k] + sizes[k + 1])) ** 3 for k in range(len(sizes) - 1)]
    total, acc = sum(weights), 0.0
    for k, w in enumerate(weights):
        acc += w / total
        psd_classes.append((acc, sizes[k], sizes[k + 1]))


def volume_of(body):
    """A powder sphere's volume (one size: the same number as sphere_volume, to the bit)."""
    return 4.0 / 3.0 * math.pi * body.shape.radius ** 3 if PSD else sphere_volume


def drawn_radius():
    """The radius of a sphere added to the fed heap: one size, R; a size distribution, a draw by
    number (a class by its number weight, then log-uniform within it)."""
    if not PSD:
        return R
    u = feed_rng.random()
    chosen = next((c for c in psd_classes if u <= c[0]), psd_classes[-1])
    return 0.5 * chosen[1] * (chosen[2] / chosen[1]) ** feed_rng.random()
if P["substrate"] == "rough":
    extend_substrate(L + P["substrate_ahead"] * d)

# Hertz normal, Mindlin tangential with the Coulomb cap; viscous damping set by YADE from the
# restitution coefficient (en, es); rolling resistance (ScGeom6D geometry) only when asked for.
# Adhesion (DMT) through the same law when adhesion_gamma > 0: YADE's Ip2 sets each contact's
# adhesionForce = 4 pi gamma R* (R* = r1 r2 / (r1 + r2) for two spheres, and R/2 for a sphere on a
# box too, as in its Hertz contact), the pull-off force of DMT with a work of adhesion 2 gamma
# (tests/case/test_adhesion_yade.py pulls two spheres, and a sphere off a box, apart and reads it);
# the law subtracts it from the Hertz force while the bodies overlap and drops the contact at zero
# overlap. adhesion_gamma is the real surface energy times density_scale (the renderer's), so the
# scaled weight keeps the real Bond number. It applies to every contact: sphere pairs, the
# substrate, the floor, the blade, and the frictionless side walls (which hold a sphere against them
# with a pair's pull-off and let it slide), unless side_walls_adhesive is false (unstick_side_walls).
ip2 = Ip2_FrictMat_FrictMat_MindlinPhys(en=P["restitution"], es=P["restitution"])
law = Law2_ScGeom_MindlinPhys_Mindlin()
if P["adhesion_gamma"] > 0.0:
    ip2.gamma = P["adhesion_gamma"]
    law.includeAdhesion = True
geometry_functors = [Ig2_Sphere_Sphere_ScGeom(), Ig2_Box_Sphere_ScGeom()]
if P["rolling_resistance"]:
    ip2.krot = P["rolling_stiffness"]
    ip2.eta = P["rolling_friction"]
    law.includeMoment = True
    geometry_functors = [Ig2_Sphere_Sphere_ScGeom6D(), Ig2_Box_Sphere_ScGeom6D()]


def unstick_side_walls():
    """Every step, right after the contact law: a sphere-side-wall contact has no adhesion. YADE's Ip2
    gives a new contact adhesionForce = 4 pi gamma R* (its `gamma` is one for every contact) and the
    law subtracts it from the normal force in the very step the contact is made; here, in that same
    step, its adhesion goes back onto both bodies (the law put -adhesionForce x normal on id2, its
    opposite on id1) and is set to 0, so that the law treats it as a dry Hertz contact from then on.
    Exact for a frictionless wall (no shear force, which adhesion would cap otherwise) approached
    by the sphere, as a new contact is (the law's viscous cap for adhesive contacts then binds
    nowhere), and without rolling resistance (whose moment cap reads the normal force: refused
    together by spreadmap.case.scene). Run only with side_walls_adhesive false and adhesion on."""
    for wall in side_wall_ids:
        for contact in O.interactions.withBody(wall):
            phys = contact.phys
            if phys.adhesionForce != 0.0:
                pull = phys.adhesionForce * contact.geom.normal
                O.forces.addF(contact.id2, pull)
                O.forces.addF(contact.id1, -pull)
                phys.adhesionForce = 0.0


newton = NewtonIntegrator(gravity=(0, 0, -P["gravity"]), damping=P["settle_damping"], label="newton")
O.engines = [
    ForceResetter(label="reset"),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()], avoidSelfInteractionMask=AVOID_MASK, label="collider"),
    InteractionLoop(geometry_functors, [ip2], [law], label="interactions"),
] + ([PyRunner(command="unstick_side_walls()", iterPeriod=1, initRun=True, label="unstick_side_walls")]
     if P["adhesion_gamma"] > 0.0 and not P["side_walls_adhesive"] else []) + [
    newton,
    PyRunner(command="watchdog()", iterPeriod=int(P["watchdog_every"]), label="watchdog"),
    PyRunner(command="control()", iterPeriod=int(P["control_every"]), label="control"),
    PyRunner(command="monitor()", iterPeriod=int(P["monitor_every"]), label="monitor"),
    PyRunner(command="record_overlap()", iterPeriod=int(P["overlap_every"]), label="record_overlap"),
]
# With `timing` on, YADE times every engine (O.timingEnabled; a few % of overhead): the raw record
# gets each phase's seconds per engine (YADE's timers: wall-clock time of this single thread), to
# see where a sphere-step's cost goes (benchmarks/engine_profile.py). Off in the workflow's cases.
O.timingEnabled = bool(P.get("timing"))

state = {"phase": "settle", "phase_start": 0.0, "blade": None, "move_start": None,
         "peak_overlap_ratio": 0.0, "rolled_off": 0, "removed_behind_volume": 0.0, "max_speed_seen": 0.0, "status": None, "reason": "",
         "peak_overlap_by_phase": {}, "peak_overlap_free": 0.0, "peak_overlap_wedged": 0.0,
         "phase_times": {}, "snapshots": {}, "max_speed_by_phase": {}, "behind_series": [], "last_progress": wall_start,
         "phase_cost": {}, "phase_mark": None, "frozen": 0, "fed": 0, "feed_after": 0.0, "wedge_series": []}
single_particle_ke_bound = 0.5 * smallest_mass * P["max_speed"] ** 2
feed_rng = random.Random(2000003 * int(P["seed"]) + 29)  # where fed spheres drop (feed_heap)


def spheres():
    return (O.bodies[i] for i in sphere_ids)


def blade_rear_x():
    return O.bodies[state["blade"]].state.pos[0] - 0.5 * tb


def max_speed():
    return max(b.state.vel.norm() for b in spheres())


def finish(status, reason=""):
    """End the run in this step. The end state is taken here, inside the step: O.pause() makes
    O.wait() return at once, while YADE's thread still completes the step (the engines after this
    one, then iter and time advance), so whatever the main thread read of the simulation after
    O.wait() would race with that thread. No runner of this script runs after this, not even later
    in this step: the first reason to end the run is the one recorded."""
    state["status"], state["reason"] = status, reason
    close_phase_cost()
    state["end"] = end_state()
    for engine in O.engines:
        if isinstance(engine, PyRunner):
            engine.dead = True
    O.pause()


def end_state():
    """What the raw record says of the end. The step in progress ends the run: `steps` and
    `simulated_time` are the counters after it (YADE adds dt to time and 1 to iter at its end);
    positions and velocities are final already (NewtonIntegrator has run in this step)."""
    on_floor = [b for b in spheres() if x_lo <= b.state.pos[0] <= x_hi]
    # through a side wall or the floor (its top face at floor_top: under a rough substrate, spheres
    # that rolled beyond the substrate's end rest on it), or thrown far upwards
    escaped = sum(1 for b in on_floor
                  if not (-R <= b.state.pos[1] <= W + R and floor_top - R <= b.state.pos[2] <= z_hi))
    return {"steps": O.iter + 1, "simulated_time": O.time + O.dt,
            "rolled_off": len(sphere_ids) - len(on_floor),  # beyond the ends of the floor, falling
            "escaped": escaped, "max_speed": max_speed(), "kinetic_energy": utils.kineticEnergy()}


def watchdog():
    """Velocity bound, every few dozen steps. The kinetic energy (computed in C++) is a cheap
    pre-filter: it exceeds one sphere's energy at the speed bound whenever any sphere does."""
    ke = utils.kineticEnergy()
    if not math.isfinite(ke):
        finish("blown", "non-finite kinetic energy at step %d" % O.iter)
    elif ke > single_particle_ke_bound:
        vmax = max_speed()
        state["max_speed_seen"] = max(state["max_speed_seen"], vmax)
        if vmax > P["max_speed"]:
            finish("blown", "a sphere reached %.3g m/s (> max_speed %.3g m/s) at step %d, t = %.4g s"
                   % (vmax, P["max_speed"], O.iter, O.time))


def snapshot():
    """All spheres (positions, radii, velocities) and the blade at this moment."""
    pos = [list(b.state.pos) for b in spheres()]
    return {"time": O.time, "iter": O.iter, "velocities": [list(b.state.vel) for b in spheres()],
            "blade_rear_x": blade_rear_x() if state["blade"] is not None else None,
            "removed_behind_volume": state["removed_behind_volume"],
            "positions": pos, "radii": [b.shape.radius for b in spheres()]}


def volume_behind(x_rear):
    """Volume passed behind the blade: spheres behind its rear face, plus those removed after
    rolling off the back end of the floor."""
    return state["removed_behind_volume"] + sum(volume_of(b) for b in spheres() if b.state.pos[0] < x_rear)


def monitor():
    """Every monitor_every steps: the fastest sphere by phase, spheres that rolled off the ends of
    the floor (removed: they would fall and accelerate for ever; the volume of those that had passed
    behind the blade stays counted as passed), and the volume passed under the blade. (The peak
    overlap is record_overlap's, read every overlap_every steps.)"""
    by_phase = state["max_speed_by_phase"]
    by_phase[state["phase"]] = max(by_phase.get(state["phase"], 0.0), max_speed())
    fallen = [b for b in spheres() if b.state.pos[2] < -2.0 * d]
    for b in fallen:
        if state["blade"] is not None and b.state.pos[0] < blade_rear_x():
            state["removed_behind_volume"] += volume_of(b)
        state["rolled_off"] += 1
        sphere_ids.remove(b.id)
        O.bodies.erase(b.id)
    if state["phase"] == "move":
        x = blade_rear_x()
        state["behind_series"].append([O.time, x, volume_behind(x)])


def box_overlap():
    """The largest overlap / R of a sphere against a box: the floor, the side walls, the settle's
    temporary walls, the blade (their contacts only: a few hundred at most, read in Python)."""
    best = 0.0
    if not PSD:
        for bid in box_ids:
            for i in O.bodies[bid].intrs():
                if i.isReal and i.geom.penetrationDepth > best:
                    best = i.geom.penetrationDepth
        return best / R
    for bid in box_ids:
        for i in O.bodies[bid].intrs():
            if i.isReal:
                best = max(best, i.geom.penetrationDepth / radius_of(i))
    return best


def radius_of(i):
    """The radius of the sphere of a sphere-box interaction."""
    s1 = O.bodies[i.id1].shape
    return s1.radius if isinstance(s1, Sphere) else O.bodies[i.id2].shape.radius


def record_overlap():
    """The peak overlap / R every overlap_every steps, of sphere-sphere contacts (YADE's C++
    maxOverlapRatio: u_N over the reduced radius 2 r1 r2 / (r1 + r2), = R for equal spheres) and of
    sphere-box contacts (box_overlap: the floor, walls and blade, u_N over the sphere's radius) alike:
    a step short against the shortest impact (the renderer sets it from Hertz's contact duration at
    the fastest expected impact), so no impact's peak is missed, on a sphere or on a box."""
    overlap = max(yade._utils.maxOverlapRatio(), box_overlap())
    if overlap > state["peak_overlap_ratio"]:
        state["peak_overlap_ratio"] = overlap
    by_phase = state["peak_overlap_by_phase"]
    if overlap > by_phase.get(state["phase"], 0.0):
        by_phase[state["phase"]] = overlap
    attribute_overlap(overlap)


WEDGE_HOPS = 2  # spheres within this many contacts of the blade are pressed by it
WEDGE_RECORD_FLOOR = 0.03  # R: blade-pressed overlaps recorded for the jam record (free impacts stay below 0.05)


def contact_overlap(i):
    """An interaction's overlap / reduced radius (2 r1 r2 / (r1 + r2) for two spheres, the sphere's
    radius against a box)."""
    s1, s2 = O.bodies[i.id1].shape, O.bodies[i.id2].shape
    if isinstance(s1, Sphere) and isinstance(s2, Sphere):
        return i.geom.penetrationDepth * (s1.radius + s2.radius) / (2.0 * s1.radius * s2.radius)
    return i.geom.penetrationDepth / (s1.radius if isinstance(s1, Sphere) else s2.radius)


def blade_pressed_overlap():
    """The largest overlap / reduced radius of the contacts of the spheres the blade presses: those
    within WEDGE_HOPS contacts of it (the blade's own contacts included). A sphere pinned between the
    moving blade and the substrate, or a short chain of them (the blade's edge on one sphere, that
    one on a second sitting in a pocket of the substrate, under the blade: found in the study's
    flagged cases at h/d 1.3-1.65, a 9.5 % R overlap two contacts from the blade while the blade was
    pushed up). The blade is driven at its speed whatever the force, so such a wedge presses until
    the spheres squeeze out; its overlap measures that, not the time step."""
    return blade_wedge()[0]


def blade_wedge():
    """(overlap, diameter): blade_pressed_overlap's largest overlap / reduced radius and the diameter
    of the larger sphere of that contact (the wedged sphere; 0 with no contact)."""
    blade = state["blade"]
    if blade is None:
        return 0.0, 0.0
    best, size = 0.0, 0.0
    seen = {blade}
    frontier = [blade]
    for _ in range(WEDGE_HOPS + 1):  # the last pass reads the contacts of the farthest spheres
        reached = []
        for body in frontier:
            for i in O.bodies[body].intrs():
                if not i.isReal:
                    continue
                overlap = contact_overlap(i)
                if overlap > best:
                    best = overlap
                    size = 2.0 * max(O.bodies[k].shape.radius for k in (i.id1, i.id2)
                                     if isinstance(O.bodies[k].shape, Sphere))
                other = i.id2 if i.id1 == body else i.id1
                if other not in seen and O.bodies[other].mask == POWDER_MASK:
                    seen.add(other)
                    reached.append(other)
        frontier = reached
    return best, size


def record_wedge(x):
    """The jam record (spreadmap.metrics.jams reads it): at each control call of the move phase whose
    blade-pressed overlap is at least WEDGE_RECORD_FLOOR R, [control call, blade rear x, overlap / R,
    wedged sphere's diameter]. A jam is a run of such calls above the config's bound, lasting some
    travel: a sphere of the coarse tail pinned under the rigid blade and dragged."""
    overlap, size = blade_wedge()
    if overlap >= WEDGE_RECORD_FLOOR:
        state["wedge_series"].append([O.iter // int(P["control_every"]), x, overlap, size])


def attribute_overlap(overlap):
    """Split the peak overlap by cause: `wedged` when the largest overlap of this step is at a
    sphere the blade presses (blade_pressed_overlap), `free` otherwise (impacts, the pile's
    weight: what the time step and the stiffness decide, the stability bound's business). Looked
    at only when this step's overlap beats the free record, so a cheap check at most steps. While
    a wedge holds the step's largest overlap, a smaller free one in the same step goes unseen."""
    if overlap <= state["peak_overlap_free"]:
        return
    if state["phase"] == "move" and blade_pressed_overlap() >= overlap * (1.0 - 1e-9):
        state["peak_overlap_wedged"] = max(state["peak_overlap_wedged"], overlap)
    else:
        state["peak_overlap_free"] = overlap


def applied_adhesion():
    """The adhesion the contact law applies, read off YADE's contacts (not recomputed): the pull-off
    force of a sphere pair (phys.adhesionForce of the first real sphere-sphere contact) and of a
    sphere on a box, and the Bond number, a pair's pull-off over one sphere's weight (simulated
    mass x gravity: density scaling multiplies both, so it is the real powder's). With a size
    distribution, the pair read is whichever touches first: its pull-off is scaled by the reduced
    radius to a pair of D50 spheres (the law's pull-off is proportional to R*), over a D50 sphere's
    weight."""
    pair = wall = None
    pair_radius = None
    for i in O.interactions:
        if not i.isReal:
            continue
        spheres_in = isinstance(O.bodies[i.id1].shape, Sphere) + isinstance(O.bodies[i.id2].shape, Sphere)
        if spheres_in == 2 and pair is None:
            pair = i.phys.adhesionForce
            r1, r2 = O.bodies[i.id1].shape.radius, O.bodies[i.id2].shape.radius
            pair_radius = r1 * r2 / (r1 + r2)
        elif spheres_in == 1 and wall is None:
            wall = i.phys.adhesionForce
        if pair is not None and wall is not None:
            break
    weight = P["density"] * (math.pi * d ** 3 / 6.0) * P["gravity"]  # a D50 sphere's
    if PSD and pair is not None:
        pair *= 0.5 * R / pair_radius
    return {"gamma": P["adhesion_gamma"], "surface_energy": P["surface_energy"], "weight": weight,
            "pair_pull_off": pair, "wall_pull_off": wall,
            "bond_number": None if pair is None else pair / weight}


def kinetic_energy_settled():
    return utils.kineticEnergy() < P["ke_tolerance"] * ke_scale


def steady_test(x):
    """Is the flow under the blade steady? Once the blade is steady_min_travel beyond the pile, the
    spheres' worth of volume passed over the last two spans of travel (n1, then n2) must agree
    within steady_z counting-noise SDs: |n2 - n1| <= z c sqrt(n1 + n2), c the counting-noise
    constant (relative SD c / sqrt(N)). Reads the passed volume at every control step."""
    if P.get("steady_min_travel") is None:
        return False
    series = state.setdefault("approach_series", [])
    series.append((x, volume_behind(x)))
    if x < L + P["steady_min_travel"] or x - series[0][0] < 2.0 * P["steady_span"]:
        return False

    def passed_at(xq):  # the last record at or before xq
        best = series[0][1]
        for xi, vi in series:
            if xi > xq:
                break
            best = vi
        return best

    v0, v1, v2 = passed_at(x - 2.0 * P["steady_span"]), passed_at(x - P["steady_span"]), series[-1][1]
    n1, n2 = (v1 - v0) / sphere_volume, (v2 - v1) / sphere_volume
    return n1 > 0 and n2 > 0 and abs(n2 - n1) <= P["steady_z"] * P["counting_noise_c"] * math.sqrt(n1 + n2)


def engine_seconds():
    return {e.label: 1e-9 * e.execTime for e in O.engines if e.label}


def close_phase_cost():
    """The phase now ending: its steps, its mean sphere count (at its start and end) and, with
    `timing`, each engine's timer seconds (wall clock) in it."""
    mark = state["phase_mark"] or {"iter": 0, "spheres": len(sphere_ids), "engines": {}}
    now = engine_seconds() if P.get("timing") else {}
    state["phase_cost"][state["phase"]] = {
        "steps": O.iter - mark["iter"], "spheres": 0.5 * (mark["spheres"] + len(sphere_ids)),
        "bodies_at_end": len(O.bodies), "interactions_at_end": len(O.interactions),
        "contacts_at_end": O.interactions.countReal(),
        "engine_seconds": {k: v - mark["engines"].get(k, 0.0) for k, v in now.items()}}
    state["phase_mark"] = {"iter": O.iter, "spheres": len(sphere_ids), "engines": now}


def freeze_behind(x_rear):
    """Stop integrating the deposit well behind the blade (freeze_behind_d): a sphere more than
    that far behind the blade's rear face and slower than freeze_speed_ratio x the blade's speed is
    frozen where it lies (at rest, no longer dynamic, given the substrate's mask so that the
    collider pairs it with neither the substrate nor another frozen sphere, its contacts with those
    erased). It stays a body: an obstacle to any sphere still moving, in every snapshot at its
    place, in every volume count. Substrate spheres behind every moving powder sphere (by 2 d) then
    touch nothing that moves: they leave the simulation (their positions stay in the record)."""
    line = x_rear - P["freeze_behind_d"] * d
    slow = P["freeze_speed_ratio"] * P["blade_speed"]
    frozen = [b for b in spheres() if b.dynamic and b.state.pos[0] < line and b.state.vel.norm() < slow]
    for b in frozen:
        b.state.vel, b.state.angVel = (0, 0, 0), (0, 0, 0)
        b.dynamic = False
        b.mask = SUBSTRATE_MASK
    for b in frozen:
        for i in b.intrs():
            if O.bodies[i.id2 if i.id1 == b.id else i.id1].mask == SUBSTRATE_MASK:
                O.interactions.erase(i.id1, i.id2)
    state["frozen"] += len(frozen)
    if frozen and substrate["ids"]:
        moving_from = min([b.state.pos[0] for b in spheres() if b.dynamic] or [x_rear]) - 2.0 * d
        keep = []
        for sid in substrate["ids"]:
            if O.bodies[sid].state.pos[0] < moving_from:
                O.bodies.erase(sid)
            else:
                keep.append(sid)
        substrate["ids"] = keep


def feed_heap(x_rear):
    """A heap fed from above (feed_count): while the blade moves, whenever fewer than feed_count
    moving spheres are at or ahead of its rear face (the heap, and what is under the blade), the
    missing ones (at most h/d + 1 layers' worth per call, at least two, the next only once these
    have fallen onto the heap) are added in a drop zone feed_zone long that starts feed_offset ahead of the blade's
    front face, on a lattice of columns along x and rows along y (1.1 d pitch, a seeded shuffle
    and a jitter of 0.04 d): in each column, 1.05 d above the highest sphere centre within
    1.1 d of it in x (so a new sphere overlaps nothing, and falls less than a diameter onto the
    heap's surface there), further layers 1.1 d apart, moving with the blade. The heap the blade
    pushes then stays the same size whatever the window's length: a preset changes what is
    measured, not the pile. Added spheres are powder like the pile's: in every snapshot and volume
    count."""
    if O.time < state["feed_after"]:  # the last spheres added are still falling onto the heap
        return
    ahead = [b for b in spheres() if b.dynamic and b.state.pos[0] >= x_rear]
    deficit = int(P["feed_count"]) - len(ahead)
    if deficit < max(1, int(W / d)):  # feed a row's worth at a time
        return
    start = x_rear + tb + P.get("feed_offset", 0.0)
    pitch = 1.1 * d_max  # the largest sphere's diameter (one size: d)
    xs = [start + 0.5 * d_max + 0.05 * d_max + i * pitch for i in range(max(1, int((P["feed_zone"] - d_max) / pitch) + 1))]
    ys = [0.5 * d_max + 0.05 * d_max + j * pitch for j in range(max(1, int((W - d_max - 0.1 * d_max) / pitch) + 1))]
    tops = {x: max([b.state.pos[2] for b in ahead if abs(b.state.pos[0] - x) <= pitch] or [-R]) for x in xs}
    # layers at a time: about what the gap passes while they fall (at h/d 7.5 two layers a call
    # could not keep up: the heap ran down from 1.8 to 1.4 h^2 in the window), the rest at the next call
    layers = max(2, int(math.ceil(P["gap"] / d)) + 1)
    deficit = min(deficit, layers * len(xs) * len(ys))
    placed, layer = 0, 0
    while placed < deficit:
        slots = [(x, y) for x in xs for y in ys]
        feed_rng.shuffle(slots)
        for x, y in slots[:deficit - placed]:
            centre = (x + feed_rng.uniform(-0.04, 0.04) * d_max, y + feed_rng.uniform(-0.04, 0.04) * d_max,
                      tops[x] + 1.05 * d_max + layer * pitch)
            bid = O.bodies.append(utils.sphere(centre, drawn_radius(), material=frict, mask=POWDER_MASK))
            O.bodies[bid].state.vel = (P["blade_speed"], 0, 0)
            sphere_ids.append(bid)
            placed += 1
        layer += 1
    state["fed"] += placed
    # the next spheres only once these have fallen their 1.05 d (and a layer more): new spheres are
    # placed above the highest ones there, and stacked on spheres still in the air they would build
    # a tower (a smoke case at h/d 7.5 with a deficit of hundreds built one 145 d tall)
    state["feed_after"] = O.time + math.sqrt(2.0 * (1.05 + layer * 1.1) * d_max / P["gravity"])


def start_phase(name):
    close_phase_cost()
    state["phase_times"][state["phase"] + "_end"] = O.time
    state["phase"], state["phase_start"] = name, O.time
    log("phase %s at t = %.4g s, step %d" % (name, O.time, O.iter))


def control():
    global x_window_end, x_window_cap
    phase, elapsed = state["phase"], O.time - state["phase_start"]
    if phase == "settle":
        if (elapsed > 0.2 * P["settle_max_time"] and kinetic_energy_settled()) or elapsed > P["settle_max_time"]:
            state["settled_by_time"] = elapsed > P["settle_max_time"]
            state["adhesion"] = applied_adhesion()
            if P.get("stop_after") == "settle":  # a poured bed, for the packing check
                state["snapshots"]["settled"] = snapshot()
                finish("ok")
                return
            newton.damping = 0.0
            for wid in temporary_walls:
                O.bodies.erase(wid)
                box_ids.remove(wid)
            top = (max(b.state.pos[2] + b.shape.radius for b in spheres()) if PSD
                   else max(b.state.pos[2] for b in spheres()) + R)
            state["settled_top"] = top
            z_top = top + 10.0 * d
            state["blade"] = O.bodies.append(utils.box(
                (-0.5 * tb, 0.5 * W, 0.5 * (h + z_top)), (0.5 * tb, 0.5 * W + d, 0.5 * (z_top - h)),
                fixed=True, material=frict))
            box_ids.append(state["blade"])
            start_phase("relax")
    elif phase == "relax":
        if (elapsed > 0.1 * P["relax_max_time"] and kinetic_energy_settled()) or elapsed > P["relax_max_time"]:
            state["relaxed_by_time"] = elapsed > P["relax_max_time"]
            O.bodies[state["blade"]].state.vel = (P["blade_speed"], 0, 0)
            state["move_start"] = O.time
            start_phase("move")
            state["snapshots"]["blade_start"] = snapshot()
    elif phase == "move":
        x = blade_rear_x()
        record_wedge(x)
        if P.get("move_steps_limit") and O.iter - state["phase_mark"]["iter"] >= P["move_steps_limit"]:
            finish("stopped", "profile: %d steps of the move phase" % P["move_steps_limit"])
            return
        if P.get("freeze_behind_d") is not None and O.iter % (10 * int(P["control_every"])) == 0:
            freeze_behind(x)
        if P.get("feed_count"):
            feed_heap(x)
        if P["substrate"] == "rough" and x + tb + L + P["substrate_ahead"] * d > substrate["x_end"]:
            extend_substrate(x + tb + L + P["substrate_ahead"] * d + 10.0 * d)
        if "window_start" not in state["snapshots"]:
            steady = steady_test(x)
            if x >= x_window_start or steady:
                x_window_end = x + P["window_travel"]
                x_window_cap = x + window_longest
                state["window_opened_by"] = "steady flow" if steady else "transient cap"
                state["snapshots"]["window_start"] = snapshot()
                state["window_start_volume"] = volume_behind(x)
                log("measurement window opens at t = %.4g s, blade %.1f d beyond the pile (%s)"
                    % (O.time, (x - L) / d, state["window_opened_by"]))
        elif adaptive_window:
            passed = (volume_behind(x) - state["window_start_volume"]) / sphere_volume
            if "window_middle" not in state["snapshots"] and passed >= 0.5 * P["target_passed"]:
                state["snapshots"]["window_middle"] = snapshot()
            if x >= x_window_end and (passed >= P["target_passed"] or x >= x_window_cap):
                state["window_closed_by"] = "target" if passed >= P["target_passed"] else "travel cap"
                if "window_middle" not in state["snapshots"]:
                    state["snapshots"]["window_middle"] = snapshot()
                state["snapshots"]["window_end"] = snapshot()
                monitor()
                finish("ok")
        elif "window_middle" not in state["snapshots"] and x >= x_window_end - 0.5 * P["window_travel"]:
            state["snapshots"]["window_middle"] = snapshot()
        elif "window_middle" in state["snapshots"] and x >= x_window_end:
            state["window_closed_by"] = "travel"
            state["snapshots"]["window_end"] = snapshot()
            monitor()
            finish("ok")
    now = time.time()
    if now - state["last_progress"] >= P["progress_every_s"]:
        state["last_progress"] = now
        travel = ("blade %.1f of %.1f d " % ((blade_rear_x() + tb) / d, (x_window_cap + tb) / d)
                  if phase == "move" else "")
        total = " of ~%d" % P["estimated_steps"] if P.get("estimated_steps") else ""
        log("progress %s phase=%s t=%.4g s steps=%d%s %swall=%.0f s"
            % (POINT, phase, O.time, O.iter, total, travel, now - wall_start))


log("start: %d spheres d = %.1f um%s, gap %.1f um, v = %.2f mm/s, f = %.3f, dt = %.3e s (%.3f of Rayleigh %.3e s)"
    % (P["n_particles"], d * 1e6, " (D50; %.1f-%.1f um, span %.2f)" % (d_min * 1e6, d_max * 1e6, P["size_span"]) if PSD else "",
       h * 1e6, P["blade_speed"] * 1e3, P["friction"], O.dt, O.dt / dt_crit, dt_crit))
O.run()
O.wait()

# From here on, only what finish() recorded: nothing is read from the simulation (see finish).
end = state["end"]
raw = {
    "format": "spreadmap-raw-1",
    "status": state["status"],
    "reason": state["reason"],
    "params": P,
    "yade_version": yade.config.version,
    "n_particles": int(P["n_particles"]),
    "time_step": O.dt,
    "critical_time_step": dt_crit,
    "time_step_ratio": O.dt / dt_crit,
    "steps": end["steps"],
    "simulated_time": end["simulated_time"],
    "wall_time": time.time() - wall_start,
    "phase_times": state["phase_times"],
    "settled_top": state.get("settled_top"),
    "settled_by_time": state.get("settled_by_time"),
    "relaxed_by_time": state.get("relaxed_by_time"),
    "move_start": state["move_start"],
    "window": {"x_start": (state["snapshots"].get("window_start") or {}).get("blade_rear_x", x_window_start), "x_end": (state["snapshots"].get("window_end") or {}).get("blade_rear_x", x_window_end),
               "x_cap": x_window_cap, "closed_by": state.get("window_closed_by"),
               "opened_by": state.get("window_opened_by"),
               "target_passed": P.get("target_passed")},
    "substrate": {"positions": substrate["positions"], "radii": substrate["radii"]},
    "geometry": {"floor_top": floor_top, "width": W, "gap": h, "blade_thickness": tb, "blade_top": state.get("settled_top", 0.0) + 10.0 * d,
                 "floor_x": [x_lo, x_hi], "pile_length": L},
    "peak_overlap_ratio": state["peak_overlap_ratio"],
    "peak_overlap_by_phase": state["peak_overlap_by_phase"],  # settle (the fall), relax, move (spreading)
    "peak_overlap_free": state["peak_overlap_free"],      # impacts and weight: the stability bound's
    "peak_overlap_wedged": state["peak_overlap_wedged"],  # a sphere the moving blade pressed
    "max_speed_seen": max(state["max_speed_seen"], end["max_speed"]),
    "final_kinetic_energy": end["kinetic_energy"],
    "kinetic_energy_scale": ke_scale,
    "escaped_particles": end["escaped"],
    "rolled_off_particles": state["rolled_off"] + end["rolled_off"],
    "max_speed_by_phase": state["max_speed_by_phase"],
    "behind_series": state["behind_series"],
    "wedge_series": state["wedge_series"],  # [control call, blade rear x, overlap / R, wedged diameter]
    "phase_cost": state["phase_cost"],
    "adhesion": state.get("adhesion"),
    "frozen_particles": state["frozen"],
    "fed_particles": state["fed"],
    "snapshots": state["snapshots"],
}
write_atomically(out_path, raw)
log("done: status %s %s; %d steps, %.4g s simulated, %.1f s wall; raw result in %s"
    % (state["status"], state["reason"], raw["steps"], raw["simulated_time"], raw["wall_time"], out_path))
sys.exit(EXIT_OK if state["status"] in ("ok", "stopped") else EXIT_BLOWN)
