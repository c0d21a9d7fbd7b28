"""Dynamics from Python, like for like with MuJoCo: the same rover — same bodies,
joints, masses, inertias, step — driving 0.15 m/s on flat ground and through fields of 20 and 100
box rocks, in our ODE simulator on M90 soil (Bekker–Wong) and in MuJoCo on rigid ground with the
same boxes. MuJoCo's wheels meet the ground as spheres of the wheel radius: one contact per wheel
on flat ground, as ours (a cylinder touches MuJoCo's plane at two points: 8 contacts against our
4). Against the rocks MuJoCo is timed twice:
- "our wheel shape" (the like-for-like figure): the wheel meets the rocks as
  ours does, as a cylinder of the wheel's radius and width, with one contact per wheel-rock pair
  as ours (MuJoCo's multi-point convex collision, multiccd, off; our collider's points are merged
  into one contact per pair). The sphere is kept for the ground only and the cylinder for the
  rocks only (contype / conaffinity), so on flat ground both MuJoCo models are the same;
- "sphere wheels": the sphere meets the rocks too, a different and much cheaper
  collision (sphere-box) than ours (cylinder-box), and a sphere touches a rock where a wheel of
  width 0.13 m does not.
Prints microseconds per step (medians of interleaved repeats, stepping loops in C in both) and our
time over MuJoCo's per scenario. MuJoCo's chassis box does not collide (ours can: it never
touches these rocks).

Our default (SimOptions.obstacle_substeps = 1) takes a step touching a rock as one step, split
into up to 8 substeps only after a step in which a wheel's slip grew fast (a wheel surging up a
rock face: obstacle_contacts.cpp). The rock scenarios are timed with the default (what training
runs) and with 8 substeps on every rock step, for comparison. The default steps the bodies with
our own island step (SimOptions.stepper = Own); every scenario is also timed with ODE's
dWorldStep (Ode). The rock scenarios are also timed with the exact wheel–rock contact
(SimOptions.wheel_obstacle_contact = Exact, cpp/dynamics/cylinder_box.hpp; not the default).

    pip install mujoco          (benchmark-only extra: pip install '.[bench]')
    ./run bench dynamics        (runs bench_dynamics.cpp, then this script)
    python benchmarks/bench_dynamics.py --steps 800 --repeats 11
"""

import argparse
import math
import os
import platform
import statistics
import sys

import numpy as np

from ernest_cpp import dynamics as D
from bench_util import median_us, rolling_rover

SPEED = 0.15  # [m/s]
CYL_Y = "0.7071067811865476 0.7071067811865476 0 0"  # a cylinder's axis (local z) onto the axle (y)
# Scenario name -> number of rocks. The rocks are D.rock_field(n, seed=7, length=2, x0=0.8): box
# rocks 6-16 cm, half buried, in x in [0.8, 2.8] m, |y| <= 1 m, the stretch the rover drives
# over in one repeat (each repeat restarts from the same state in both simulators).
SCENARIOS = {"flat M90": 0, "M90 + 20 rocks": 20, "M90 + 100 rocks": 100}
DEFAULT_SUBSTEPS = D.SimOptions().obstacle_substeps
OTHER_SUBSTEPS = 8 if DEFAULT_SUBSTEPS == 1 else 1  # the comparison column


def rocks(n: int) -> list:
    return D.rock_field(n, seed=7, length=2.0, width=2.0, x0=0.8)


def mjcf(p: D.RoverParameters, dt: float, boxes, wheel_shape: str = "sphere") -> str:
    """MJCF of the ERNEST model of cpp/dynamics (rover frame: origin between the wheel centres),
    and the rocks as static boxes. wheel_shape "sphere": sphere wheels against ground and rocks;
    "ours": a sphere against the ground (contype / conaffinity 2) and the wheel's cylinder
    against the rocks (1), one contact per pair (multiccd off), as our simulator."""
    if wheel_shape not in ("sphere", "ours"):
        raise ValueError(f"wheel_shape must be 'sphere' or 'ours', not {wheel_shape!r}")
    ours_shape = wheel_shape == "ours"
    r = p.wheel_radius
    cc, ci, bi = p.chassis_com, p.chassis_inertia, p.bogie_inertia
    g = p.gimbal_point()
    spin = p.wheel_spin_inertia
    # Our wheel body carries the rotor reflected through the gear (J_r N^2) on its spin axis;
    # MuJoCo's equivalent is the joint armature.
    armature = p.wheel_motor.rotor_inertia * p.wheel_motor.gear_ratio ** 2
    wt = p.wheel_transverse_inertia
    box_c = np.array([-0.05, 0.0, 0.375])

    def wheel(name, pos):
        return (f'<body name="{name}" pos="{pos[0]} {pos[1]} {pos[2]}">'
                f'<joint name="{name}_j" type="hinge" axis="0 1 0" armature="{armature}"/>'
                f'<inertial pos="0 0 0" mass="{p.wheel_assembly_mass}" diaginertia="{wt} {spin} {wt}"/>'
                + (f'<geom type="sphere" size="{r}" contype="2" conaffinity="2"/>'
                   f'<geom type="cylinder" size="{r} {p.wheel_width / 2}" quat="{CYL_Y}"/>'
                   if ours_shape else f'<geom type="sphere" size="{r}"/>') + '</body>')

    def box(b):
        c, s, q = b.centre, b.size, (math.cos(b.yaw / 2), 0.0, 0.0, math.sin(b.yaw / 2))
        return (f'<geom type="box" pos="{c[0]} {c[1]} {c[2]}" size="{s[0] / 2} {s[1] / 2} {s[2] / 2}" '
                f'quat="{q[0]} {q[1]} {q[2]} {q[3]}"/>')

    flags = '<flag multiccd="disable"/>' if ours_shape else ""
    ground = ' contype="2" conaffinity="2"' if ours_shape else ""
    fl = p.wheel_centre(0) - g
    fr = p.wheel_centre(1) - g
    z0 = r + 0.005
    return f"""
<mujoco model="ernest">
  <option timestep="{dt}" gravity="0 0 -9.81" integrator="implicitfast">{flags}</option>
  <default><geom friction="0.8 0.005 0.0001"/></default>
  <worldbody>
    <geom name="ground" type="plane" size="50 50 0.1"{ground}/>
    {''.join(box(b) for b in boxes)}
    <body name="chassis" pos="0 0 {z0}">
      <freejoint/>
      <inertial pos="{cc[0]} {cc[1]} {cc[2]}" mass="{p.chassis_mass}" diaginertia="{ci[0]} {ci[1]} {ci[2]}"/>
      <geom type="box" pos="{box_c[0]} {box_c[1]} {box_c[2]}" size="0.4 0.275 0.125" contype="0" conaffinity="0"/>
      {wheel("rl", p.wheel_centre(2))}
      {wheel("rr", p.wheel_centre(3))}
      <body name="bogie" pos="{g[0]} {g[1]} {g[2]}">
        <joint name="yaw" type="hinge" axis="0 0 1" range="-45 45"/>
        <joint name="roll" type="hinge" axis="1 0 0" range="-30 30"/>
        <inertial pos="0 0 {p.bogie_com_height - g[2]}" mass="{p.bogie_mass}" diaginertia="{bi[0]} {bi[1]} {bi[2]}"/>
        {wheel("fl", fl)}
        {wheel("fr", fr)}
      </body>
    </body>
  </worldbody>
  <actuator>
    <velocity joint="fl_j" kv="200"/><velocity joint="fr_j" kv="200"/>
    <velocity joint="rl_j" kv="200"/><velocity joint="rr_j" kv="200"/>
    <velocity joint="yaw" kv="2000"/><velocity joint="roll" kv="2000"/>
  </actuator>
</mujoco>"""


def ours(boxes, substeps: int, stepper=None, contact=None):
    """Our rover on M90 with these rocks, rolling at SPEED after 50 steps: (sim, start snapshot)."""
    sim = rolling_rover(boxes, SPEED, substeps, stepper=stepper, contact=contact)
    sim.step_n(50)
    return sim, sim.snapshot()


class Mujoco:
    """The same rover in MuJoCo, rolling at SPEED after 50 steps; reset() returns to that state."""

    def __init__(self, mujoco, p, dt, boxes, wheel_shape="sphere"):
        self.mj = mujoco
        self.model = mujoco.MjModel.from_xml_string(mjcf(p, dt, boxes, wheel_shape))
        self.data = mujoco.MjData(self.model)
        self.ctrl = SPEED / p.wheel_radius
        self.data.ctrl[:4] = self.ctrl
        self.data.qvel[0] = SPEED
        self.data.qvel[6:] = 0.0
        mujoco.mj_step(self.model, self.data, 50)
        self.qpos, self.qvel = self.data.qpos.copy(), self.data.qvel.copy()
        self.act, self.warm = self.data.act.copy(), self.data.qacc_warmstart.copy()

    def contacts(self, steps):
        """Steps from the start state one at a time: (most ground contacts, most contacts of one
        geom pair) seen, to check the like-for-like claims (4 and 1 for our wheel shape)."""
        self.reset()
        m, d = self.model, self.data
        plane = self.mj.mj_name2id(m, self.mj.mjtObj.mjOBJ_GEOM, "ground")
        ground, per_pair = 0, 0
        for _ in range(steps):
            self.mj.mj_step(m, d)
            pairs = {}
            for c in d.contact[:d.ncon]:
                pairs[(c.geom1, c.geom2)] = pairs.get((c.geom1, c.geom2), 0) + 1
            ground = max(ground, sum(1 for c in d.contact[:d.ncon] if plane in (c.geom1, c.geom2)))
            per_pair = max([per_pair] + list(pairs.values()))
        return ground, per_pair

    def reset(self):
        d = self.data
        self.mj.mj_resetData(self.model, d)
        d.qpos[:], d.qvel[:], d.act[:], d.qacc_warmstart[:] = self.qpos, self.qvel, self.act, self.warm
        d.ctrl[:4] = self.ctrl

    def run(self, steps):
        self.mj.mj_step(self.model, self.data, steps)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=800, help="steps per repeat (10 s at 0.0125 s)")
    ap.add_argument("--repeats", type=int, default=11)
    args = ap.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}, "
          f"load average {os.getloadavg()[0]:.1f}")
    try:
        import mujoco
    except ImportError:
        print("mujoco not installed (pip install mujoco): comparison skipped")
        return 0
    p = D.RoverParameters()
    dt = D.SimOptions().dt
    steps, repeats = args.steps, args.repeats
    # Interleaved repeats (every variant once per round) so that load changes on a shared machine
    # hit all alike; medians of the per-repeat times and of the per-repeat ratios.
    runs = {}
    for name, n in SCENARIOS.items():
        boxes = rocks(n)
        # on flat ground both MuJoCo models are the sphere-wheeled one (nothing for a cylinder to hit)
        runs[(name, "mujoco")] = Mujoco(mujoco, p, dt, boxes, "ours" if n else "sphere")
        if n:
            runs[(name, "mujoco_sphere")] = Mujoco(mujoco, p, dt, boxes, "sphere")
        for sub in ((DEFAULT_SUBSTEPS, OTHER_SUBSTEPS) if n else (DEFAULT_SUBSTEPS,)):
            sim, start = ours(boxes, sub)
            runs[(name, sub)] = (sim, start)
        runs[(name, "ode")] = ours(boxes, DEFAULT_SUBSTEPS, D.Stepper.Ode)
        if n:
            runs[(name, "exact")] = ours(boxes, DEFAULT_SUBSTEPS,
                                         contact=D.WheelObstacleContact.Exact)
    for name, n in SCENARIOS.items():  # one contact per wheel on the ground and per wheel-rock pair
        ground, per_pair = runs[(name, "mujoco")].contacts(steps)
        if ground > 4 or per_pair > 1:
            print(f"MuJoCo model not like for like in {name}: {ground} ground contacts, "
                  f"{per_pair} contacts of one pair")
            return 1
    print("checked: MuJoCo (our wheel shape) makes at most 4 ground contacts and one contact per "
          "geom pair in every step of every scenario, as ours")
    t = {k: [] for k in runs}
    travelled = {}
    for _ in range(repeats):
        for key, r in runs.items():
            if key[1] in ("mujoco", "mujoco_sphere"):
                r.reset()
                x0 = float(r.data.qpos[0])
                t[key].append(median_us(lambda: r.run(steps), steps, repeats=1))
                travelled[key] = float(r.data.qpos[0]) - x0
                if r.data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0:
                    print(f"MuJoCo run unstable in {key[0]}: comparison invalid")
                    return 1
            else:
                sim, start = r
                sim.restore(start)
                x0 = sim.state.position[0]
                t[key].append(median_us(lambda: sim.step_n(steps), steps, repeats=1))
                travelled[key] = sim.state.position[0] - x0
    med = {k: statistics.median(v) for k, v in t.items()}

    def ratio(name, sub, ref="mujoco"):
        return statistics.median(a / b for a, b in zip(t[(name, sub)], t[(name, ref)]))

    print(f"MuJoCo {mujoco.__version__} (implicitfast, rigid plane, rocks as boxes; wheels: spheres "
          f"on the ground, against the rocks our wheel's cylinder with one contact per pair, or "
          f"spheres) against ours (ODE, M90 soil, Bekker-Wong), dt = {dt} s, {steps} steps x "
          f"{repeats} interleaved repeats, driving {SPEED} m/s")
    print(f"| scenario | MuJoCo us/step, our wheel shape | ours us/step, default "
          f"({DEFAULT_SUBSTEPS} obstacle substep(s)) | ratio | MuJoCo us/step, sphere wheels | "
          f"ratio | ours us/step, {OTHER_SUBSTEPS} obstacle substep(s) | ratio | "
          "ours us/step, ODE's dWorldStep | ratio | ours us/step, Exact wheel-rock contact | ratio | "
          "travelled ours / MuJoCo (our shape / spheres) [m] |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, n in SCENARIOS.items():
        on = f"{med[(name, DEFAULT_SUBSTEPS)]:.2f} | **{ratio(name, DEFAULT_SUBSTEPS):.2f}**"
        sph = (f"{med[(name, 'mujoco_sphere')]:.2f} | {ratio(name, DEFAULT_SUBSTEPS, 'mujoco_sphere'):.2f}"
               if n else "(no rocks: same) | —")
        off = (f"{med[(name, OTHER_SUBSTEPS)]:.2f} | {ratio(name, OTHER_SUBSTEPS):.2f}" if n
               else "(no rocks: same) | —")
        ode = f"{med[(name, 'ode')]:.2f} | {ratio(name, 'ode'):.2f}"
        exact = (f"{med[(name, 'exact')]:.2f} | {ratio(name, 'exact'):.2f}" if n
                 else "(no rocks: same) | —")
        far = f"{travelled[(name, 'mujoco')]:.2f}" + (
            f" / {travelled[(name, 'mujoco_sphere')]:.2f}" if n else "")
        print(f"| {name} | {med[(name, 'mujoco')]:.2f} | {on} | {sph} | {off} | {ode} | {exact} | "
              f"{travelled[(name, DEFAULT_SUBSTEPS)]:.2f} / {far} |")
    print("ratio = ours / MuJoCo (our wheel shape unless marked), median of the per-repeat ratios "
          "(target <= 1.0)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
