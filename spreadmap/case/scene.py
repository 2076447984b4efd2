"""Derive every number of one spreading case from its design point, its fidelity preset and the
configuration: the parameters that the YADE scene script receives (SI units).

Domain sizes are in particle diameters (d). The time step is a fraction (`dt_factor`) of the
Rayleigh critical step of Hertzian contact for the particles' radius and the density used in the
simulation; a forced step above the critical one is refused here, before anything runs.
"""
from __future__ import annotations

import math

from ..design import NAMES
from . import psd

# Densest sphere packing: no solid fraction can exceed it.
DENSEST_PACKING = math.pi / (3.0 * math.sqrt(2.0))  # 0.7405


class UnsafeTimeStep(ValueError):
    """A forced time step above the critical step of a case.

    A ValueError raised by ``time_step`` (so by ``scene_parameters`` and
    ``spreadmap.case.identity.case_scene``) before anything runs; its message names the config key,
    the forced and the critical step.
    """


def rayleigh_time_step(radius: float, density: float, young: float, poisson: float) -> float:
    """Rayleigh critical step of Hertzian contact: pi R sqrt(rho/G) / (0.1631 nu + 0.8766)."""
    shear = young / (2.0 * (1.0 + poisson))
    return math.pi * radius * math.sqrt(density / shear) / (0.1631 * poisson + 0.8766)


def hertz_contact_time(radius: float, density: float, material: dict, speed: float) -> float:
    """Duration of an elastic Hertz impact of two equal spheres at relative speed `speed`:
    2.868 (m*^2 / (R* E*^2 v))^(1/5), with m* = m/2, R* = R/2, E* = E / (2 (1 - nu^2))
    (Johnson, Contact Mechanics, 1985, sec. 11.4). Damping (e < 1) lengthens it a little."""
    mass = density * 4.0 / 3.0 * math.pi * radius ** 3
    e_star = material["young_pa"] / (2.0 * (1.0 - material["poisson"] ** 2))
    return 2.868 * ((0.5 * mass) ** 2 / (0.5 * radius * e_star ** 2 * speed)) ** 0.2


def overlap_stride(contact: float, time_step: float, reads_per_contact: int) -> int:
    """Steps between two reads of the peak overlap: 1 / `reads_per_contact` of the shortest contact the
    scene expects (`contact`, ``hertz_contact_time``), at least 1; `reads_per_contact` is the preset's
    overlap_reads_per_contact (the schema's default a quarter, issue 50, every eighth before; the shipped
    presets' half since 2026-12-07; the tests' `smoke` a third, 2 steps)."""
    return max(1, int(contact / (reads_per_contact * time_step)))


def configured_counting_c(config: dict) -> float:
    """c of the counting noise, a case's relative SD of MFR = c / sqrt(N) (config
    metrics.counting_noise_c; validation fills the schema's default)."""
    return float(config["metrics"]["counting_noise_c"])


def precision_target(preset: dict, config: dict) -> float | None:
    """Spheres that must pass under the blade in the window for the relative SD of MFR the preset asks for.

    N = (c / target_cv)^2, rounded up, with c the counting noise's constant (a case's relative SD of
    MFR = c / sqrt(N)).

    Parameters
    ----------
    preset : dict
        A preset of the config (``presets.<name>``): its ``target_cv`` [-], the relative SD of MFR
        asked for; absent or None: a fixed window.
    config : dict
        The loaded configuration: ``metrics.counting_noise_c`` [-].

    Returns
    -------
    float or None
        N, a whole number of spheres; None when the preset has a fixed window.
    """
    cv = preset.get("target_cv")
    if cv is None:
        return None
    return math.ceil((configured_counting_c(config) / cv) ** 2)


def time_step(diameter: float, density: float, material: dict, preset: dict, preset_name: str) -> tuple[float, float]:
    """(time step, critical step) for a case; refuses a forced step above the critical one."""
    critical = rayleigh_time_step(0.5 * diameter, density, material["young_pa"], material["poisson"])
    forced = preset.get("time_step_s")
    if forced is None:
        return preset["dt_factor"] * critical, critical
    if forced > critical:
        raise UnsafeTimeStep(
            f"config key 'presets.{preset_name}.time_step_s': value {forced:g} s is above the Rayleigh "
            f"critical step {critical:.3e} s of a case with d = {diameter * 1e6:.3g} um at density "
            f"{density:g} kg/m3; it must be below the critical step (the study's fixed 1e-6 s blows up "
            f"at every diameter in range). Remove it to use dt_factor x critical step.")
    return forced, critical


def standing_reserve_h2(scene: dict, d: float, h: float, f: float | None = None) -> float:
    """The fed heap's standing reserve at a design point, in units of h^2 of bulk powder.

    ``scene.pile_reserve`` x h^2, or with ``scene.pile_reserve_d2`` set and the friction at or above
    ``scene.pile_reserve_d2_from_f``, that many d^2 kept between ``scene.pile_reserve_min`` and
    ``scene.pile_reserve`` h^2. 40 d^2 read as 4.7 h^2 within +-3 % at three points of f 0.30-0.45,
    h/d 4.3-5.8, 35 % low at f 0.16, h/d 5.2, and 7 % low at f 0.31, h/d 6.5 (docs/heap_size): the
    shipped config sets no d^2 heap.

    Parameters
    ----------
    scene : dict
        The config's ``scene`` section, validated (``pile_reserve``, ``pile_reserve_d2``,
        ``pile_reserve_min``, ``pile_reserve_d2_from_f``).
    d, h : float
        The sphere diameter (the D50) and the gap [m].
    f : float, optional
        The friction coefficient [-]; needed when ``pile_reserve_d2`` is set and
        ``pile_reserve_d2_from_f`` is above 0.

    Returns
    -------
    float
        The reserve [h^2].
    """
    most = float(scene["pile_reserve"])
    per_d2 = scene["pile_reserve_d2"]
    if per_d2 is None:
        return most
    from_f = float(scene["pile_reserve_d2_from_f"])
    if from_f > 0.0:
        if f is None:
            raise ValueError("scene.pile_reserve_d2_from_f is set: the heap's size needs the point's friction f")
        if f < from_f:
            return most
    least = min(float(scene["pile_reserve_min"]), most)
    return min(most, max(least, float(per_d2) * (d / h) ** 2))


# Material parameters the scene passes on as they are: PARAMS key <- config key of `material` (SI
# units, as the schema gives them). A new one is a line here, the schema's key, and the template's
# use of it (docs/guide/06-workflow.md, "Adding a material parameter").
MATERIAL = {"young": "young_pa", "poisson": "poisson", "restitution": "restitution", "gravity": "gravity_m_s2"}
# How often the scene's runners run, in steps (the watchdog's speed bound, the phase control, the monitor).
CADENCES = {"watchdog_every": 50, "control_every": 100, "monitor_every": 1000}


def _lengths(point: dict) -> tuple[float, float, float]:
    """(d, h, v) of a design point in SI units: diameter and gap [m], blade speed [m/s]."""
    return point["d_um"] * 1e-6, point["h_um"] * 1e-6, point["v_mm_s"] * 1e-3


def _check_point(point: dict, case_id: str) -> None:
    for key in NAMES:
        value = point[key]
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"case {case_id}: parameter {key} = {value!r} must be a positive number")


def material_parameters(point: dict, preset: dict, material: dict, scene: dict) -> dict:
    """The spheres' physics: friction, density (x the preset's density_scale), elastic constants,
    restitution, gravity, DMT adhesion, the size distribution and rolling resistance.

    Parameters
    ----------
    point : dict
        The design point (``f`` [-], ``d_um`` [um], ...).
    preset : dict
        The preset (``density_scale``).
    material, scene : dict
        The validated config's ``material`` and ``scene`` sections.

    Returns
    -------
    dict
        ``friction``, ``density`` [kg/m3], ``density_scale``, the ``MATERIAL`` keys, ``surface_energy``
        [J/m2] and ``adhesion_gamma`` (the one the scene applies: x density_scale, as the weight, so
        the Bond number is the real powder's), ``size_span``, ``psd_sizes`` [m] and ``psd_cumulative``
        (empty: one size), ``rolling_resistance``, ``rolling_friction`` and ``rolling_stiffness``
        [N m/rad], ``side_walls_adhesive``.

    Raises
    ------
    ValueError
        If the side walls are not adhesive (``scene.side_walls_adhesive`` false) with rolling
        resistance on: the scene cannot take the adhesion off such a contact exactly.
    """
    d = point["d_um"] * 1e-6
    scale = float(preset["density_scale"])
    sizes = material["size_distribution"]
    # the size distribution (d is its D50): sieve sizes [m] and cumulative volume fractions
    sieves, fractions = psd.sieve_table(d, float(sizes["span"]), sizes["tails"])
    surface_energy = float(material["surface_energy_j_m2"])
    rolling = scene["rolling_resistance"]
    if not scene["side_walls_adhesive"] and rolling["enabled"]:
        raise ValueError("config key 'scene.side_walls_adhesive': false is exact only without rolling resistance "
                         "(the first step of a side-wall contact caps its rolling moment by the adhesive normal "
                         "force); set scene.rolling_resistance.enabled false, or side_walls_adhesive true")
    # rolling stiffness: stiffness_factor x (Hertz normal stiffness at an overlap of 1e-3 R) x R^2
    r = 0.5 * d
    e_star = material["young_pa"] / (2.0 * (1.0 - material["poisson"] ** 2))
    k_n = 2.0 * e_star * math.sqrt(0.5 * r * 1e-3 * r)
    return {
        "friction": float(point["f"]),
        # a float whether the config spells it 7980 or 7980.0: one case (spreadmap.case.identity)
        "density": float(material["density_kg_m3"] * scale),
        "density_scale": scale,
        **{key: float(material[name]) for key, name in MATERIAL.items()},
        "surface_energy": surface_energy,
        "adhesion_gamma": surface_energy * scale,
        "size_span": float(sizes["span"]),
        "psd_sizes": sieves,
        "psd_cumulative": fractions,
        "rolling_resistance": bool(rolling["enabled"]),
        "rolling_friction": float(rolling["rolling_friction"]),
        "rolling_stiffness": float(rolling["stiffness_factor"]) * k_n * r * r,
        # false: the slice's side walls do not stick (yade_scripts/spreading_case.py, unstick_side_walls)
        "side_walls_adhesive": bool(scene["side_walls_adhesive"]),
    }


def window_parameters(point: dict, preset: dict, config: dict) -> dict:
    """Where the measurement window opens and how long it lasts.

    It opens once the flow is steady, at least ``steady_min_d`` beyond the pile (None: after the fixed
    ``transient_d``), comparing the flow over two spans of ``steady_span_d``; it measures
    ``window_d``, or with a precision target (``target_cv``) until ``target_passed`` spheres have
    passed, up to ``window_max_d``. Spheres at rest ``freeze_behind_d`` behind the blade are frozen.

    Parameters
    ----------
    point : dict
        The design point (``d_um`` [um]).
    preset : dict
        The preset.
    config : dict
        The validated config (``scene``, ``metrics.counting_noise_c``).

    Returns
    -------
    dict
        ``transient_travel``, ``window_travel``, ``window_max_travel``, ``steady_min_travel``,
        ``steady_span`` [m]; ``target_passed`` (spheres; None: a fixed window), ``steady_z``,
        ``counting_noise_c``, ``freeze_behind_d``, ``freeze_speed_ratio``.
    """
    d = point["d_um"] * 1e-6
    scene = config["scene"]
    target = precision_target(preset, config)
    window = preset["window_d"] * d
    return {
        "transient_travel": preset["transient_d"] * d,
        "window_travel": window,
        "target_passed": None if target is None else float(target),
        "window_max_travel": window if target is None else max(window, preset["window_max_d"] * d),
        "steady_min_travel": None if preset["steady_min_d"] is None else preset["steady_min_d"] * d,
        "steady_span": float(scene["steady_span_d"]) * d,
        "steady_z": float(scene["steady_z"]),
        "counting_noise_c": configured_counting_c(config),
        "freeze_behind_d": None if scene["freeze_behind_d"] is None else float(scene["freeze_behind_d"]),
        "freeze_speed_ratio": float(scene["freeze_speed_ratio"]),
    }


def _sphere_volume(d: float, material: dict) -> float:
    """A sphere's mean volume by number [m3] at D50 d (one size: pi d^3 / 6)."""
    sizes = material["size_distribution"]
    return math.pi * d ** 3 / 6.0 * psd.mean_volume_ratio(float(sizes["span"]), sizes["tails"])


def expected_window_travel(point: dict, preset: dict, config: dict, window: dict) -> float:
    """The window's expected travel [m]: a fixed window's length; with a target, the travel in which
    the target's spheres pass at the expected MFR (``scene.mfr_expected``), between the window's
    length and its cap."""
    if window["target_passed"] is None:
        return window["window_travel"]
    d, h, _ = _lengths(point)
    width = preset["width_d"] * d
    passing = window["target_passed"] * _sphere_volume(d, config["material"]) / (config["scene"]["mfr_expected"] * h * width)
    return min(window["window_max_travel"], max(window["window_travel"], passing))


def domain_parameters(point: dict, preset: dict, config: dict, window: dict) -> dict:
    """The domain: the slice's width, the pile (sized so that its heap outlasts the window), the cloud
    it falls from, the fed heap, the floor and the substrate.

    The heap ahead of the blade holds ``heap_reserve`` times the most solid the gap can take (a layer
    of height h at the densest packing) while the blade travels the transient, the window and its own
    thickness; with a precision target the pile is sized by what will pass, times a margin, plus a
    standing heap of ``standing_reserve_h2`` x h^2. A fed heap (scene.fed_heap) is topped up ahead
    of the blade during the move, so the pile holds only what passes before the window plus that reserve.

    Parameters
    ----------
    point : dict
        The design point (``f`` [-], ``d_um`` and ``h_um`` [um]).
    preset : dict
        The preset.
    config : dict
        The validated config (``scene``, ``material``).
    window : dict
        The case's ``window_parameters``.

    Returns
    -------
    dict
        ``width``, ``pile_length``, ``pile_height``, ``cloud_height``, ``blade_thickness``,
        ``floor_ahead`` (in d), ``feed_zone``, ``feed_offset`` [m]; ``n_particles``, ``feed_count``
        (spheres; None without a fed heap); ``substrate``, ``substrate_jitter`` (of R) and
        ``substrate_ahead`` (in d).
    """
    scene = config["scene"]
    d, h, _ = _lengths(point)
    width = preset["width_d"] * d
    blade = scene["blade_thickness_d"] * d
    transient = window["transient_travel"]
    heap = preset["heap_height_d"] * d
    packing = scene["packing_guess"]
    sphere_volume = _sphere_volume(d, config["material"])
    fed = bool(scene["fed_heap"])
    reserve = standing_reserve_h2(scene, d, h, float(point["f"]))
    if window["target_passed"] is None:
        need = preset["heap_reserve"] * DENSEST_PACKING * h * (transient + (0.0 if fed else window["window_travel"]) + blade)
        if fed:  # the pile starts with the heap it will be fed to hold (a smaller one would be fed at once)
            need += reserve * h * h * packing * heap / (h + heap)
    else:
        target = window["target_passed"]  # a whole number of spheres
        # The whole pile is sized by what will pass: the target's spheres plus what passes in the
        # transient and under the blade at a generous MFR, times a margin (not the densest
        # packing); expressed per unit width, as the heap-reserve rule above, over the pile's height
        mfr_high = scene["mfr_expected_max"]
        # scene.feed_transient (with the fed heap): the transient's passing is fed too, not piled:
        # the pile holds what fills the gap under the blade and the standing reserve, and the feed
        # starts with the blade (the pile held the transient's passing and settled with it: a 5 d
        # transient cost 1.28x the CPU of 3 d where the travel alone said 1.07x, docs/steady_window)
        # presets.<name>.pile_transient_d (with the fed heap): the pile holds what passes in this much
        # travel beyond it, not in the whole transient; the feed tops the heap up beyond it, so a window
        # opened later costs its travel only (null: the transient itself)
        if fed and scene["feed_transient"]:
            before_window = blade
        elif fed and preset["pile_transient_d"] is not None:
            before_window = preset["pile_transient_d"] * d + blade
        else:
            before_window = transient + blade
        need = scene["pile_margin"] * ((0.0 if fed else target * sphere_volume / width) + mfr_high * h * before_window)
        need *= heap / (h + heap)  # the whole pile, not only its heap above the gap, is the reserve
        # ... plus a standing heap that is never meant to pass: the flow under the blade stays
        # steady only while the heap ahead of it is tall against the gap, a wedge at the angle of
        # repose whose area grows as h^2 (docs/precision: a pile of what passes x 1.5 at h/d = 7.5
        # fed a flow that fell from 0.5 to 0.1 within the window). Its area is `reserve` x h^2.
        need += reserve * h * h * packing * heap / (h + heap)
    pile_length = max(preset["pile_length_min_d"] * d, need / (packing * heap))
    pile_height = h + heap
    n_particles = int(round(packing * pile_length * width * pile_height / sphere_volume))
    # makeCloud keeps sphere centres one radius inside the box: size the cloud on that inner box
    # so that it holds n_particles at `cloud_fraction` (it silently places fewer when too tight).
    # (A size distribution: each sphere keeps its own radius inside, the D50's on average. Sizing on
    # the largest sphere's instead made the cloud of a pile 2 d long 7x taller at span 1, D50 45 um:
    # a fall at 0.43 m/s into the pile, overlaps of 8 % R.)
    inner = (pile_length - d) * (width - d)
    substrate = scene["substrate"]
    return {
        "width": width,
        "pile_length": pile_length,
        "pile_height": pile_height,
        "cloud_height": n_particles * sphere_volume / (scene["cloud_fraction"] * inner) + d,
        "n_particles": n_particles,
        "blade_thickness": blade,
        "floor_ahead": float(scene["floor_ahead_d"]),
        # the fed heap's size: the standing reserve (pile_reserve x h^2 of bulk powder) plus what
        # fills the gap under the blade, in spheres
        "feed_count": (int(round(packing * width * (reserve * h * h + blade * h) / sphere_volume))
                       if fed else None),
        "feed_zone": float(scene["feed_zone_d"]) * d,
        "feed_offset": float(scene["feed_offset_d"]) * d,
        "substrate": substrate["kind"],
        "substrate_jitter": float(substrate["jitter"]),
        "substrate_ahead": float(substrate["ahead_d"]),
    }


def stepping_parameters(point: dict, preset: dict, preset_name: str, config: dict, physics: dict,
                        window: dict, domain: dict) -> dict:
    """The time stepping: the step (``dt_factor`` x the Rayleigh critical step of the smallest
    sphere, unless the preset forces one), the settle and relax phases' longest times, the shortest
    contact expected and the stride of the peak overlap's reads, and the run's step estimate and
    outer timeout.

    Parameters
    ----------
    point : dict
        The design point (``d_um`` [um], ``v_mm_s`` [mm/s]).
    preset, preset_name : dict, str
        The preset and its name (named in ``UnsafeTimeStep``'s message).
    config : dict
        The validated config (``material``, ``scene``).
    physics, window, domain : dict
        The case's ``material_parameters``, ``window_parameters`` and ``domain_parameters``.

    Returns
    -------
    dict
        ``time_step``, ``critical_time_step``, ``settle_max_time``, ``relax_max_time``,
        ``contact_time`` [s], ``overlap_every`` (steps), ``estimated_steps`` and ``timeout_s`` [s]
        (bookkeeping: not keyed, spreadmap.case.identity).

    Raises
    ------
    UnsafeTimeStep
        If the preset forces a time step above the case's critical step.
    """
    material, scene = config["material"], config["scene"]
    d, _, v = _lengths(point)
    g, density = physics["gravity"], physics["density"]
    # the step is the smallest sphere's
    d_min = physics["psd_sizes"][0] if physics["psd_sizes"] else d
    dt, dt_crit = time_step(d_min, density, material, preset, preset_name)
    cloud_height, pile_height = domain["cloud_height"], domain["pile_height"]
    settle_max = scene["settle_time_factor"] * math.sqrt(2.0 * cloud_height / g)
    relax_max = scene["relax_time_factor"] * math.sqrt(2.0 * pile_height / g)
    ahead = domain["blade_thickness"] + domain["pile_length"] + window["transient_travel"]
    steps = (settle_max + relax_max + (ahead + expected_window_travel(point, preset, config, window)) / v) / dt
    longest_steps = (settle_max + relax_max + (ahead + window["window_max_travel"]) / v) / dt
    timeout = preset.get("timeout_s") or 60.0 + scene["timeout_factor"] * domain["n_particles"] * longest_steps / 2.0e6
    # the fastest impact expected: the fall of the cloud's top onto the pile, or a sphere thrown
    # ahead of the blade at a few times its speed
    impact_speed = max(math.sqrt(2.0 * g * cloud_height), 4.0 * v)
    contact = hertz_contact_time(0.5 * d_min, density, material, impact_speed)
    return {
        "time_step": dt,
        "critical_time_step": dt_crit,
        "settle_max_time": settle_max,
        "relax_max_time": relax_max,
        # the peak overlap is read every overlap_every steps, at most 1 / overlap_reads_per_contact of
        # the shortest contact expected (half since 2026-12-07: 4 steps at `default`, x~1.4; a quarter
        # before, 2 steps, x1.05-1.09; a third at the tests' `smoke`: 2 steps, x1.09-1.11); the
        # stability check multiplies what it read by the factor a Hertz peak can exceed the nearest
        # sample (spreadmap.metrics.case's overlap_sampling_factor): never laxer than reading every
        # step; stricter by up to the factor where a read falls on the peak (a free peak of 0.039 R
        # read at x1.43 was flagged in a main job: docs/main_job); every step cost 15-18 % of a case's CPU
        # (docs/case_cost), every second 0.866x that, every fourth 0.92x every second (docs/steady_window)
        "overlap_every": overlap_stride(contact, dt, int(preset["overlap_reads_per_contact"])),
        "contact_time": contact,
        "estimated_steps": int(steps),
        "timeout_s": float(timeout),
    }


def run_parameters(point: dict, preset_name: str, scene: dict, case_id: str, seed: int | None) -> dict:
    """What names and controls the run: the case's id, point (and in SI units: ``diameter``, ``gap``
    [m], ``blade_speed`` [m/s]), preset and packing seed, the settle phase's damping and rest test,
    the watchdog's speed bound, the runners' cadences, the progress line's cadence (bookkeeping) and
    no early stop."""
    return {
        "case_id": case_id,
        "point": {k: float(point[k]) for k in NAMES},
        "preset": preset_name,
        "seed": int(scene["seed"] if seed is None else seed),
        **dict(zip(("diameter", "gap", "blade_speed"), _lengths(point))),
        "settle_damping": float(scene["settle_damping"]),
        "ke_tolerance": float(scene["ke_tolerance"]),
        "max_speed": float(scene["max_speed_m_s"]),
        **CADENCES,
        "progress_every_s": float(scene["progress_every_s"]),
        "stop_after": None,
    }


def scene_parameters(point: dict, preset_name: str, config: dict, case_id: str, seed: int | None = None) -> dict:
    """The PARAMS dict of the YADE scene script for design point `point` at preset `preset_name`.

    Every number is derived from the point, the preset and the validated configuration, in SI units,
    by its part: the run (``run_parameters``), the spheres' physics (``material_parameters``), the
    measurement window (``window_parameters``), the domain (``domain_parameters``, sizes in particle
    diameters) and the time stepping (``stepping_parameters``: ``dt_factor`` x the Rayleigh critical
    step, unless the preset forces one; see the module docstring).

    Parameters
    ----------
    point : dict
        The design point: ``f`` [-], ``d_um`` [um], ``h_um`` [um], ``v_mm_s`` [mm/s].
    preset_name : str
        The preset (a key of the config's ``presets``).
    config : dict
        The loaded configuration (``spreadmap.config.load``: validated, the schema's defaults
        filled): presets, material, scene, metrics.
    case_id : str
        The id written into the parameters (``case_id``) and named in error messages.
    seed : int or None, optional
        The packing seed; None: the scene's (config ``scene.seed``).

    Returns
    -------
    dict
        The PARAMS of the scene script, SI units: among them ``case_id``, ``point`` (as given, floats),
        ``diameter`` and ``gap`` [m], ``blade_speed`` [m/s], ``density`` [kg/m3], ``time_step`` and
        ``critical_time_step`` [s], the domain (``width``, ``pile_length``, ``pile_height``,
        ``cloud_height`` [m]), ``n_particles``, ``seed``, ``preset``, ``timeout_s`` [s], the floor
        (``substrate``, ``substrate_jitter``) and the window's target ``target_passed`` (spheres; None
        with a fixed window).

    Raises
    ------
    ValueError
        If a parameter of the point is not a positive finite number.
    UnsafeTimeStep
        If the preset forces a time step (``time_step_s``) above the case's critical step.
    KeyError
        If ``preset_name`` is not a preset of the config.
    """
    _check_point(point, case_id)
    preset = config["presets"][preset_name]
    physics = material_parameters(point, preset, config["material"], config["scene"])
    window = window_parameters(point, preset, config)
    domain = domain_parameters(point, preset, config, window)
    stepping = stepping_parameters(point, preset, preset_name, config, physics, window, domain)
    return {**run_parameters(point, preset_name, config["scene"], case_id, seed), **physics, **window, **domain, **stepping}
