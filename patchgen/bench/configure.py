"""The engine's configuration: profiles, scenario and ``ideal`` resolved into the records the
compiled loop takes (patchgen.bench.engine.EngineConfig), with the step, the noise processes, the
drift, the actuator model and the disturbances, and a readable account of them (SimSettings)."""

from __future__ import annotations

import math

import numpy as np

from patchgen.bench import bench_spread as bs
from patchgen.bench.circuit import INTEGRATOR, SUMMER, Circuit
from patchgen.bench.engine import EngineConfig, default_step, noise_process
from patchgen.bench.kernel import (
    DIST_CART_FORCE,
    DIST_STEP,
    DIST_TIP_FORCE,
    Disturbances,
    Noise,
    Sensors,
    Settings,
    Wiring,
)
from patchgen.bench.lanes import (
    A_DEAD_ZONE,
    A_FORCE_LIMIT,
    A_K_U,
    ACT_GAIN,
    ACT_LAG,
    ACT_LAG_ZERO,
    ACT_MOTOR,
    PLANT_CART,
    PLANT_ROTARY,
    input_groups,
)
from patchgen.bench.noise_drift import NoiseAndDrift, noise_and_drift
from patchgen.bench.results import SimSettings
from patchgen.inputs.drive_fields import LAG_MODELS, motor_of
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import Scenario, check_plant
from patchgen.plant.compiled import P_HALF_TRACK, VECTOR_PARAMETERS, plant_vector
from patchgen.plant.drive import with_rotor
from patchgen.plant.equations import PlantParams
from patchgen.plant.plant_model import CART, PLANT_MODELS, model_of
from patchgen.plant.rotary_compiled import rotary_vector
from patchgen.plant.rotary_equations import RotaryParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.profiles.measured_plant import as_on_bench

LIMIT_TOL = 1e-9  # relative: an actuator limit at the rails, as a motor's a V_limit / (a amp_gain) computes it
# the plant vector's first parameters (d: half track), those a --spread may draw
SPREAD_ORDER = tuple(k for k in VECTOR_PARAMETERS if k not in ("J", "F_C"))


def engine_config(circuit: Circuit, plant: PlantParams | RotaryParams, bench: BenchProfile,
                  machine: MachineProfile, scenario: Scenario, *,
                  ideal: bool = False, spread: dict[str, float] | None = None,
                  bench_spread: bool = False, rails: bool = True) -> tuple[EngineConfig, SimSettings]:
    """Resolve profiles, scenario and ``ideal`` into the engine's records, and a readable account.

    Parameters
    ----------
    circuit : Circuit
        The compiled netlist.
    plant : PlantParams or RotaryParams
        The nominal plant (a cart or a rotary pendulum: the bench's own).
    bench, machine : BenchProfile, MachineProfile
        The actuator, sensors and track; the machine's imperfections.
    scenario : Scenario
        Duration, step, noise, drift, disturbances, initial state.
    ideal : bool
        Every imperfection off (see patchgen.bench.simulate).
    spread : dict of str to float, optional
        Per plant parameter (SPREAD_ORDER's names), the fraction within which each run draws it.
    bench_spread : bool
        Each run draws its bench from the profile's ``[uncertainty]`` ranges (those the
        simulation feels: patchgen.bench.bench_spread.active_ranges).
    rails : bool
        False: no amplifier clips at its rails, every other imperfection kept: the patch's signals
        as its linear circuit makes them (what a scaling for signal-to-noise scales).

    Returns
    -------
    EngineConfig, SimSettings
        What the engine runs, and what was simulated, in words and SI units.
    """
    spread = dict(spread or {})
    plant = as_on_bench(plant, bench)
    pm = model_of(plant)
    if pm is not CART and any(spread.values()):
        raise InputError("--spread", "", f"draws a cart's parameters; {pm.name}'s are not spread yet")
    ranges = bs.active_ranges(bench, ideal, scenario.noise.mode == "profile") if bench_spread else {}
    fastest = [1.0 / v for v in circuit.time_rates() + circuit.internal_rates() if v > 0]
    motor = motor_of(bench.actuator)
    if not ideal and bench.actuator.model in LAG_MODELS:
        fastest.append(min(bench.actuator.tau, ranges.get("tau", (math.inf,))[0]))
    if not ideal and motor is not None:
        fastest.append(motor.electrical_lag())
    fastest += [1.0 / (f.wn_rad_s * f.zeta) for f in bench.sensors.filters().values()]
    step = scenario.dt_s or default_step(fastest, ideal)
    n_steps = max(1, math.ceil(scenario.duration_s / step - 1e-9))
    step = scenario.duration_s / n_steps
    stride = max(1, round(scenario.record_dt_s / step))
    imp = machine.imperfections

    if pm is CART:
        scenario = scenario.on_track(plant.d)  # an offset or step given as a fraction of the track, in metres
        scenario = scenario.on_pendulum(plant)  # a push at a stated point of the pendulum: on the cart and at l
    else:
        scenario = scenario.on_arm(plant)  # a push at a stated point of the pendulum: at the tip and the arm's end
    check_plant(scenario, pm, "this run")  # another plant's scenario: named, not simulated
    levels = noise_and_drift(circuit.sensor_ids, bench, machine, scenario, ideal)
    sensor_rms, amp_rms, drift = levels.sensor_V_rms, levels.amplifier_V_rms, levels.drift_V_per_s
    s_proc = [noise_process(sensor_rms[s], levels.sensor_bandwidth_Hz, step)
              for s in circuit.sensor_ids]
    a_proc = noise_process(amp_rms, levels.amplifier_bandwidth_Hz, step)
    f_proc = [noise_process(rms, levels.force_bandwidth_Hz, step)
              for rms in (levels.cart_force_N_rms, levels.tip_force_N_rms)]
    unit_std = {}  # a drawn noise level: the channel's process per unit rms
    n_ch = circuit.n_sensors + circuit.n_amps
    for key in ranges:
        if key.startswith("noise_V_rms."):
            chans = tuple(i for i, sid in enumerate(circuit.sensor_ids) if sid == key.split(".", 1)[1])
            unit = noise_process(1.0, levels.sensor_bandwidth_Hz, step)
            for i in chans:
                s_proc[i] = (unit[0], s_proc[i][1])
        elif key in ("cart_force_N_rms", "tip_force_N_rms"):
            k = 0 if key == "cart_force_N_rms" else 1
            chans, unit = (n_ch + k,), noise_process(1.0, levels.force_bandwidth_Hz, step)
            f_proc[k] = (unit[0], f_proc[k][1])
        else:
            continue
        unit_std[key] = (chans, unit[1])

    act = bench.actuator
    emf = 0.0 if motor is None else motor.back_emf_damping()
    if ideal:
        model, tau, dead, flim = (ACT_GAIN if motor is None else ACT_MOTOR), 0.0, 0.0, math.inf
        act_text = f"ideal: pure gain K_U = {act.K_U} {pm.input_unit}/V (no lag, dead zone or limit)"
        if motor is not None:
            act_text += f", with the motor's back-EMF ({emf:.6g} N s/m) and rotor"
    elif motor is not None:
        model, tau, dead, flim = ACT_MOTOR, motor.electrical_lag(), act.dead_zone_V, act.force_limit_N
        act_text = (f"dc_motor: K_U = {act.K_U:.6g} N/V, back-EMF {emf:.6g} N s/m, rotor "
                    f"{motor.referred_mass():.6g} kg on the cart, electrical lag {tau:g} s, dead zone +/-{dead} V, "
                    f"amplifier limit +/-{act.V_limit:g} V (force {flim:.6g} N)")
    else:
        model = {"gain": ACT_GAIN, "lag": ACT_LAG, "lag_zero": ACT_LAG_ZERO}[act.model]
        tau, dead, flim = act.tau, act.dead_zone_V, act.force_limit_N
        if model != ACT_GAIN and tau <= 0:
            if model == ACT_LAG_ZERO:
                raise InputError(f"bench {bench.id}", "actuator.tau",
                                 "model lag_zero needs tau > 0")
            model = ACT_GAIN
        act_text = (f"{act.model}: K_U = {act.K_U} {pm.input_unit}/V, tau = {tau} s, "
                    f"dead zone +/-{dead} V, {pm.input_noun} limit +/-{flim} {pm.input_unit}")

    if pm is CART:
        cut = bench.track.cut_at(plant.d)  # where the switches or the watchdog cut the motor
        vector = _with_cut(plant_vector(with_rotor(plant, motor)), cut)
    else:  # the run ends where the cable winds up (none: a slip ring)
        cut = plant.alpha_limit if math.isfinite(plant.alpha_limit) else None
        vector = rotary_vector(plant)
    kinds, t0s, t1s, vals = [], [], [], []
    for d in scenario.disturbances:
        if d.kind == "step":
            kinds.append(DIST_STEP)
            t0s.append(d.time_s)
            t1s.append(math.inf)
            vals.append(d.step_size())
            continue
        for kind, value in _pushes(d, plant):
            kinds.append(kind)
            t0s.append(d.time_s)
            t1s.append(d.time_s + d.duration_s)
            vals.append(value)

    groups = input_groups(circuit.in_ptr, circuit.in_src, circuit.in_gain,
                          zero_row=circuit.n_sensors + circuit.n_amps + len(f_proc))  # sig's zero row
    cfg = EngineConfig(
        settings=Settings(
            dt=float(step), steps=int(n_steps), stride=int(stride), saturation=float(imp.saturation_V),
            clip=not ideal and rails, limit_switches=cut is not None,
            fall_angle=math.radians(scenario.fall_angle_deg), output=int(circuit.output_index),
            x0=np.array(scenario.initial.vector(pm), dtype=np.float64),
            actuator=int(model), plant=PLANT_CART if pm is CART else PLANT_ROTARY),
        sensors=_sensors(circuit, bench, ideal),
        noise=Noise(a=_f64([p[0] for p in s_proc] + [a_proc[0]] * circuit.n_amps + [p[0] for p in f_proc]),
                    std=_f64([p[1] for p in s_proc] + [a_proc[1]] * circuit.n_amps + [p[1] for p in f_proc])),
        wiring=Wiring(kind=_i64(circuit.amp_kind), in_ptr=_i64(circuit.in_ptr), in_src=_i64(circuit.in_src),
                      in_gain=_f64(circuit.in_gain), param1=_f64(circuit.param1),
                      param2=_f64(circuit.param2), ic=_f64(circuit.ic_V),
                      drift=_f64(_drifts(circuit, levels, machine)), group_ptr=groups[0], group_src=groups[1],
                      group_gain=groups[2]),
        disturbances=Disturbances(kind=_i64(kinds), t0=_f64(t0s), t1=_f64(t1s), value=_f64(vals)),
        plant=vector,
        plant_spread=_f64([spread.get(k, 0.0) for k in SPREAD_ORDER] if pm is CART else []),
        actuator=_f64([act.K_U, tau, dead, flim, emf]),
        bench_spread=bs.plan(ranges, bench.uncertainty.distribution,
                             tuple(pm.state_names[q] for q in circuit.sensor_state), circuit.sensor_ids, unit_std),
    )
    settings = SimSettings(
        dt_s=step, steps=n_steps, record_dt_s=stride * step,
        sensor_noise_V_rms=sensor_rms, sensor_noise_bandwidth_Hz=levels.sensor_bandwidth_Hz,
        amplifier_noise_V_rms=amp_rms, amplifier_noise_bandwidth_Hz=levels.amplifier_bandwidth_Hz,
        integrator_drift_V_per_s=drift,
        cart_force_N_rms=levels.cart_force_N_rms, tip_force_N_rms=levels.tip_force_N_rms,
        force_bandwidth_Hz=levels.force_bandwidth_Hz,
        saturation_V=imp.saturation_V, saturation_clipped=not ideal and rails,
        actuator=act_text, limit_switches=bool(bench.track.limit_switches),
        half_track_m=plant.d / 2 if pm is CART else cut, watchdog_m=bench.track.watchdog_m,
        plant_spread={k: v for k, v in spread.items() if v},
        bench_spread={k: list(v) for k, v in ranges.items()},
        bench_distribution=bench.uncertainty.distribution if ranges else None, plant=pm.name,
        measured_plant=dict(bench.measured_plant),
    )
    return cfg, settings


def harmless_overloads(circuit: Circuit, cfg: EngineConfig) -> tuple[str, ...]:
    """The amplifier whose excursion past the rails is the actuator's saturation, not a fault: the
    command's, when it is a summer (no state to wind up) driving an actuator limited before any
    dynamics of its own (a gain, a motor's amplifier) whose limit, in command volts (dead zone
    included, at the lowest K_U a run may draw), lies within the rails. Clipped at the rail, it
    asks no less than the actuator gives; the run reports its time at the limit instead."""
    st = cfg.settings
    j = st.output - circuit.n_sensors
    if j < 0 or not st.clip or circuit.amp_kind[j] != SUMMER or st.actuator not in (ACT_GAIN, ACT_MOTOR):
        return ()
    ranges = cfg.bench_spread.ranges if cfg.bench_spread is not None else {}
    k_u = ranges.get("K_U", (cfg.actuator[A_K_U],))[0]
    f_lim = ranges.get("force_limit_N", (0.0, cfg.actuator[A_FORCE_LIMIT]))[1]
    dead = ranges.get("dead_zone_V", (0.0, cfg.actuator[A_DEAD_ZONE]))[1]
    within = f_lim / k_u + dead <= st.saturation * (1.0 + LIMIT_TOL)
    return (circuit.amp_ids[j],) if within else ()


def _with_cut(vector: np.ndarray, cut: float | None) -> np.ndarray:
    """The plant vector with the run's end at the motor's cut (the watchdog's, when nearer than the
    switches at half the track)."""
    if cut is not None:
        vector[P_HALF_TRACK] = cut
    return vector


def _sensors(circuit: Circuit, bench: BenchProfile, ideal: bool) -> Sensors:
    """The sensors as the bench has them: each reads its plant state, or a filter's rate of a
    position; an encoder's count where the profile states one (patchgen.profiles.bench), unless
    ideal (a count is a measurement's imperfection, as noise is; a filter is the sensor itself)."""
    quanta, filters = ({} if ideal else bench.sensors.quanta()), bench.sensors.filters()
    order = sorted(filters)  # a filter per filtered quantity, in name order
    pm = PLANT_MODELS[bench.plant]
    states, position_of = pm.state_names, pm.position_of
    qs = [states[i] for i in circuit.sensor_state]
    filt = [order.index(q) if q in filters else -1 for q in qs]
    source = [states.index(position_of[q]) if q in filters else -1 for q in qs]
    return Sensors(state=_i64(circuit.sensor_state), gain=_f64(circuit.sensor_gain),
                   quantum=_f64([quanta.get(position_of[q] if q in filters else q, 0.0) for q in qs]),
                   filt=_i64(filt), source=_i64(source),
                   wn=_f64([filters[q].wn_rad_s if q in filters else 0.0 for q in qs]),
                   zeta=_f64([filters[q].zeta if q in filters else 0.0 for q in qs]))


def _pushes(d, plant: PlantParams | RotaryParams) -> list[tuple[int, float]]:
    """A scenario's push as the kernel's channels take it, (DIST_* kind, value): a force at the
    pendulum's tip (N), or on the position: a cart's force (N), a rotary arm's torque (N m: a push
    at its end times L_r). A push at a stated point is already shared out (Scenario.on_pendulum,
    Scenario.on_arm)."""
    if d.at == "pendulum_tip":
        return [(DIST_TIP_FORCE, d.force_N)]
    return [(DIST_CART_FORCE, d.force_N * (plant.L_r if d.at == "arm" else 1.0))]


def _drifts(circuit: Circuit, levels: NoiseAndDrift, machine: MachineProfile) -> np.ndarray:
    """Each amplifier's drift magnitude, V/s: an integrator's at its mode's rate k0 (param1), a
    lag's at the run's rate, none for the others (NoiseAndDrift.drift_at)."""
    return np.array([levels.drift_at(float(circuit.param1[j]) if k == INTEGRATOR else None, machine) if d else 0.0
                     for j, (k, d) in enumerate(zip(circuit.amp_kind, circuit.drifting()))])


def _f64(values) -> np.ndarray:
    """A contiguous float64 array, as the compiled loop takes it."""
    return np.ascontiguousarray(values, dtype=np.float64)


def _i64(values) -> np.ndarray:
    """A contiguous int64 array, as the compiled loop takes it."""
    return np.ascontiguousarray(values, dtype=np.int64)
