"""Dynamics from Python, side by side with MuJoCo (issue 3): the same rover — same bodies, joints,
masses, inertias, step — driving on flat ground with rigid contacts in MuJoCo, and in our ODE
simulator on rigid ground and on M90 soil (Bekker–Wong). Prints microseconds per step (medians of
repeats, stepping loops in C in both) and our per-step time over MuJoCo's.

    pip install mujoco          (benchmark-only extra: pip install '.[bench]')
    ./run bench dynamics        (runs bench_dynamics.cpp, then this script)
"""

import platform
import statistics
import sys

import numpy as np

from ernest_cpp import dynamics as D
from bench_util import median_us


def mjcf(p: D.RoverParameters, dt: float) -> str:
    """MJCF of the ERNEST model of cpp/dynamics (rover frame: origin between the wheel centres)."""
    r, w = p.wheel_radius, p.wheel_width
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
                f'<geom type="cylinder" size="{r} {w / 2}" zaxis="0 1 0"/></body>')

    fl = p.wheel_centre(0) - g
    fr = p.wheel_centre(1) - g
    z0 = r + 0.005
    return f"""
<mujoco model="ernest">
  <option timestep="{dt}" gravity="0 0 -9.81" integrator="implicitfast"/>
  <default><geom friction="0.8 0.005 0.0001"/></default>
  <worldbody>
    <geom name="ground" type="plane" size="50 50 0.1"/>
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


def main():
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}")
    p = D.RoverParameters()
    steps, repeats = 500, 11
    dt = D.SimOptions().dt
    sims = {}
    for ground in ("rigid", "soil"):
        sim = D.make_sim(ground, friction=0.8)
        sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.15)
        c = D.Commands()
        c.wheel_speed = [0.15 / p.wheel_radius] * 4
        sim.set_commands(c)
        sim.step_n(50)
        sims[ground] = sim
    try:
        import mujoco
    except ImportError:
        mujoco = None
        print("mujoco not installed (pip install mujoco): comparison skipped")
    if mujoco is not None:
        model = mujoco.MjModel.from_xml_string(mjcf(p, dt))
        data = mujoco.MjData(model)
        data.ctrl[:4] = 0.15 / p.wheel_radius
        mujoco.mj_step(model, data, 50)
        x0 = float(data.qpos[0])
    # Interleaved repeats (ours rigid, ours soil, MuJoCo) so that load changes on a shared machine
    # hit all three alike; medians of the per-repeat times and of the per-repeat ratios.
    t = {"rigid": [], "soil": [], "mujoco": []}
    for _ in range(repeats):
        for ground, sim in sims.items():
            t[ground].append(median_us(lambda: sim.step_n(steps), steps, repeats=1))
        if mujoco is not None:
            t["mujoco"].append(median_us(lambda: mujoco.mj_step(model, data, steps), steps, repeats=1))
    med = {k: statistics.median(v) for k, v in t.items() if v}
    print(f"ours (ODE), dt = {dt} s: rigid ground {med['rigid']:.2f} us/step, "
          f"M90 soil {med['soil']:.2f} us/step")
    if mujoco is None:
        return 0
    if data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0 or data.qpos[0] - x0 < 1.0:
        print("MuJoCo run was unstable or did not drive: comparison invalid")
        return 1
    print(f"MuJoCo {mujoco.__version__}, same rover, rigid contacts, dt = {dt} s: "
          f"{med['mujoco']:.2f} us/step (travelled {data.qpos[0] - x0:.2f} m)")
    r_rigid = statistics.median(a / b for a, b in zip(t["rigid"], t["mujoco"]))
    r_soil = statistics.median(a / b for a, b in zip(t["soil"], t["mujoco"]))
    print(f"ratio ours / MuJoCo (median of {repeats} interleaved repeats): rigid {r_rigid:.2f}, "
          f"M90 soil {r_soil:.2f} (target <= 1.0)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
