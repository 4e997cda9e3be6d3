"""The flexible structure in the MuJoCo twin (``structure.mode = "flexible"``).

The same discrete model as the reference engine (:mod:`twin.structure`), as a MuJoCo body tree:

* the connecting rod is :func:`twin.structure.rod_chain`'s chain: the body ``rod`` is its root
  ``end_B`` (the housing at B: its mass and rotary inertia, the bore at B, the rod's rigid-body joints
  ``rod_hinge`` and, with a clearance at B, ``ecc_B_x/y``), then the segments ``rod_seg_1`` …
  ``rod_seg_N`` and ``rod_end_C`` (the housing at C, the bore at C), each the child of the previous,
  its frame at its joint node on the straight rod; the chain's elastic joints (``rod_bend_i`` hinges
  about z, ``rod_axial_i`` slides along the child's x axis, hinge before slide at a node) carry the
  chain's stiffness and Rayleigh dampers as MuJoCo joint ``stiffness`` and ``damping`` (spring
  reference 0: the straight rod). The base model's options keep ``eulerdamp`` disabled, so the dampers
  enter the step explicitly, as in the reference's symplectic Euler (the configuration's stability
  check, :func:`twin.structure.checks.check_structure`, bounds ω h for that);
* the crank's support (the frame at A): the body ``frame_support`` on the world with two slides
  ``frame_x``, ``frame_y`` (stiffness k = m (2π f)², damping c = 2 ζ m 2π f, both axes), mass
  ``structure.frame_mass_kg`` at A; the crank (its hinge) rides on it;
* the slider's support (the guide rails): the body ``guide_support`` on the world with the slide
  ``guide_y`` normal to the guide, mass ``structure.guide_mass_kg``; the slider (its guide slide)
  rides on it;
* the accelerometers' sites sit on the chain body holding their abscissa
  (:func:`twin.structure.rod._body_at`), at the same point of the straight rod as in the rigid model;
  the engine filters their sampled readings with the mount (:class:`twin.structure.MountFilter`).

The bores at B and C keep their names (``bushing_B`` on ``rod``, ``bushing_C`` on ``rod_end_C``):
the native module finds pin and bore through their geoms' bodies (``geom_bodyid``, the velocity
of a material point from the body's chain), so both contact sources ("law" rows and "force") work
unchanged on the flexible rod; the eccentricity sensors at B and C read the pin in the frame of the
bore's own body (the end housing).

Body nesting is changed on the base model's XML (``xml.etree``: MjSpec cannot move a body of the
same spec) before MjSpec reads it; the numbers are then written through MjSpec by :func:`finish`.
The rigid model never passes through here.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import mujoco

from twin import names
from twin.config import BenchConfig
from twin.errors import ConfigError


def applies(cfg: BenchConfig) -> bool:
    return cfg.structure.flexible


def check(cfg: BenchConfig) -> None:
    """What the MuJoCo flexible model does not offer: one-line ConfigError naming the field."""
    if cfg.joints.diametral_mm("A") > 0:
        raise ConfigError("joints.clearance_a_mm", "a clearance at A is not available with structure.mode = "
                          "\"flexible\" in the MuJoCo engine (the crank pivot rides on the frame's support); "
                          f"use 0, got {cfg.joints.clearance_a_mm!r}")
    if cfg.joints.guide_play:
        raise ConfigError("joints.clearance_guide_mm", "a guide clearance is not available with structure.mode = "
                          "\"flexible\" (the guide's support carries the slider's transverse compliance); use 0, "
                          f"got {cfg.joints.clearance_guide_mm!r}")
    if cfg.mujoco.bushing != "bore":
        raise ConfigError("mujoco.bushing", "must be \"bore\" with structure.mode = \"flexible\", got "
                          f"{cfg.mujoco.bushing!r}")


def chain_of(cfg: BenchConfig):
    """The damped rod chain of ``cfg`` (:func:`twin.structure.rod_chain`)."""
    from twin.structure import rod_chain

    return rod_chain(cfg.structure, cfg.bodies.rod, cfg.bodies.slider.mass_kg)


def body_name(chain_body: str) -> str:
    """MuJoCo body of a chain body name (``end_B`` is the rod's own body)."""
    if chain_body == "end_B":
        return names.ROD
    if chain_body == "end_C":
        return names.ROD_END_C
    return names.rod_segment(int(chain_body.split("_")[1]))


def joint_names(chain) -> list[str]:
    """MuJoCo names of the chain's joints, in the chain's order."""
    out, nh, ns = [], 0, 0
    for j in chain.joints:
        if j.kind == "hinge":
            nh += 1
            out.append(names.rod_bend(nh))
        else:
            ns += 1
            out.append(names.rod_axial(ns))
    return out


# ------------------------------------------------------------------------------------ XML nesting
def _find(parent: ET.Element, tag: str, name: str) -> ET.Element:
    for el in parent.iter(tag):
        if el.get("name") == name:
            return el
    raise KeyError(f"{tag} {name!r} not in {names.BASE_XML}")


def _parent_map(root: ET.Element) -> dict[ET.Element, ET.Element]:
    return {c: p for p in root.iter() for c in p}


def _slide(name: str, axis: str) -> ET.Element:
    return ET.Element("joint", {"name": name, "type": "slide", "axis": axis})


def flexible_xml(cfg: BenchConfig) -> str:
    """The base model's XML with the flexible structure's bodies and joints nested (numbers: :func:`finish`)."""
    tree = ET.parse(str(names.BASE_XML))
    root = tree.getroot()
    world = root.find("worldbody")
    parents = _parent_map(root)
    # frame support: the crank rides on it
    crank = _find(world, "body", names.CRANK)
    frame = ET.Element("body", {"name": names.FRAME_SUPPORT, "childclass": "bench"})
    frame.append(ET.Element("inertial", {"pos": "0 0 0", "mass": "1", "diaginertia": "1e-6 1e-6 1e-6"}))
    frame.append(_slide(names.FRAME_X, "1 0 0"))
    frame.append(_slide(names.FRAME_Y, "0 1 0"))
    idx = list(world).index(crank)
    world.remove(crank)
    frame.append(crank)
    world.insert(idx, frame)
    # guide support: the slider rides on it
    slider = _find(world, "body", names.SLIDER)
    guide = ET.Element("body", {"name": names.GUIDE_SUPPORT, "childclass": "bench"})
    guide.append(ET.Element("inertial", {"pos": "0 0 0", "mass": "1", "diaginertia": "1e-6 1e-6 1e-6"}))
    guide.append(_slide(names.GUIDE_Y, "0 1 0"))
    idx = list(world).index(slider)
    world.remove(slider)
    guide.append(slider)
    world.insert(idx, guide)
    # the rod's chain under the rod body (end_B)
    chain = chain_of(cfg)
    rod = _find(world, "body", names.ROD)
    jn = iter(zip(chain.joints, joint_names(chain)))
    pending = next(jn, None)
    parent = rod
    for b, body in enumerate(chain.bodies[1:], start=1):
        el = ET.SubElement(parent, "body", {"name": body_name(body.name)})
        ET.SubElement(el, "inertial", {"pos": "0 0 0", "mass": "1", "diaginertia": "1e-6 1e-6 1e-6"})
        while pending is not None and pending[0].child == b:
            j, name = pending
            if j.kind == "hinge":
                ET.SubElement(el, "joint", {"name": name, "type": "hinge", "axis": "0 0 1"})
            else:
                ET.SubElement(el, "joint", {"name": name, "type": "slide", "axis": "1 0 0"})
            pending = next(jn, None)
        parent = el
    end_c = parent
    for tag, name in (("geom", names.bushing("C")), ("geom", names.bushing_ring("C")), ("site", names.bushing("C"))):
        el = _find(rod, tag, name)
        parents[el].remove(el)
        end_c.append(el)
    return ET.tostring(root, encoding="unicode")


# ------------------------------------------------------------------------------------------ numbers
def _inertial(body: mujoco.MjsBody, mass: float, com_x: float, izz: float) -> None:
    body.explicitinertial = True
    body.mass = mass
    body.ipos = [com_x, 0.0, 0.0]
    body.iquat = [1.0, 0.0, 0.0, 0.0]
    # planar: only I_zz acts (a point mass has none: MuJoCo needs a positive tensor, 1e-12 kg m² is
    # below the round-off of the chain's composite inertia about any of its joints); the off-plane values
    # equal it, so that the triangle inequality holds with margin also after the XML export's rounding
    izz = max(izz, 1e-12)
    body.inertia = [izz, izz, izz]


def _spring(joint: mujoco.MjsJoint, k: float, c: float) -> None:
    joint.stiffness[0] = k
    joint.damping[0] = c
    joint.springref = 0.0


def finish(spec: mujoco.MjSpec, cfg: BenchConfig) -> None:
    """Write the flexible structure's numbers into the spec of :func:`flexible_xml` (after the builder's
    rigid edits, which it overrides for the rod): the chain's masses, joints and visual beams, the bores
    and the accelerometers on their bodies, the supports, and the structure's sensors."""
    from twin.structure.rod import _body_at

    check(cfg)
    st = cfg.structure
    chain = chain_of(cfg)
    bodies = [spec.body(body_name(b.name)) for b in chain.bodies]
    for k, (cb, sb) in enumerate(zip(chain.bodies, bodies)):
        if k > 0:
            sb.pos = [cb.x0_m - chain.bodies[k - 1].x0_m, 0.0, 0.0]
        _inertial(sb, cb.mass_kg, cb.com_x_m - cb.x0_m, cb.inertia_kgm2)
    for j, name in zip(chain.joints, joint_names(chain)):
        _spring(spec.joint(name), j.stiffness, j.damping)
    # visual: one beam per segment (the rigid model's single beam goes)
    beam = spec.geom(names.ROD_BEAM)
    half_y, half_z = beam.size[1], beam.size[2]
    rgba, group = list(beam.rgba), beam.group
    spec.delete(beam)
    for k, cb in enumerate(chain.bodies[1:-1], start=1):
        half = (cb.x1_m - cb.x0_m) / 2
        bodies[k].add_geom(name=names.rod_segment_beam(k), type=mujoco.mjtGeom.mjGEOM_BOX,
                           size=[half * 0.98, half_y, half_z], pos=[half, 0.0, 0.0], contype=0, conaffinity=0,
                           mass=0, group=group, rgba=rgba)
    # the bore at C on the end housing, at its frame
    for obj in (spec.geom(names.bushing("C")), spec.geom(names.bushing_ring("C")), spec.site(names.bushing("C"))):
        obj.pos = [0.0, 0.0, 0.0]
    # accelerometers on the chain body holding their abscissa, same point of the straight rod
    for name, mount in cfg.sensors.accelerometers.items():
        if mount.body != "rod":
            continue
        x, y = mount.position_m
        b = _body_at(chain, x)
        site = spec.site(name)
        target = bodies[b]
        pos = [x - chain.bodies[b].x0_m, y, 0.0]
        if site.parent.name != target.name:
            new = target.add_site(name=f"{name}_tmp", pos=pos, quat=list(site.quat), size=list(site.size),
                                  type=site.type, rgba=list(site.rgba), group=site.group)
            spec.delete(site)
            new.name = name
        else:
            site.pos = pos
    # a marker at mid-span for the deflection channel
    xm = chain.length_m / 2
    bm = _body_at(chain, xm)
    bodies[bm].add_site(name=names.ROD_MID, pos=[xm - chain.bodies[bm].x0_m, 0.0, 0.0], size=[0.002, 0, 0],
                        group=5, rgba=[1, 0, 0, 1])
    # supports
    frame = spec.body(names.FRAME_SUPPORT)
    _inertial(frame, st.frame_mass_kg, 0.0, 0.0)
    kf = st.support_stiffness(st.frame_mass_kg, st.frame_frequency_hz)
    cf = st.support_damping(st.frame_mass_kg, st.frame_frequency_hz, st.frame_damping_ratio)
    for jn in (names.FRAME_X, names.FRAME_Y):
        _spring(spec.joint(jn), kf, cf)
    guide = spec.body(names.GUIDE_SUPPORT)
    _inertial(guide, st.guide_mass_kg, 0.0, 0.0)
    _spring(spec.joint(names.GUIDE_Y), st.support_stiffness(st.guide_mass_kg, st.guide_frequency_hz),
            st.support_damping(st.guide_mass_kg, st.guide_frequency_hz, st.guide_damping_ratio))
    # the structure's channels (optional group "structure"): the bores' centres and the mid-span point in
    # the world, the supports' displacements
    if "structure" in cfg.sensors.channels:
        for sensor, site in ((names.SENSOR_ROD_B, names.bushing("B")), (names.SENSOR_ROD_MID, names.ROD_MID),
                             (names.SENSOR_ROD_C, names.bushing("C"))):
            spec.add_sensor(name=sensor, type=mujoco.mjtSensor.mjSENS_FRAMEPOS, objtype=mujoco.mjtObj.mjOBJ_SITE,
                            objname=site)
        for sensor, joint in ((names.SENSOR_FRAME_X, names.FRAME_X), (names.SENSOR_FRAME_Y, names.FRAME_Y),
                              (names.SENSOR_GUIDE_Y, names.GUIDE_Y)):
            spec.add_sensor(name=sensor, type=mujoco.mjtSensor.mjSENS_JOINTPOS, objtype=mujoco.mjtObj.mjOBJ_JOINT,
                            objname=joint)


def structure_channels(col, length_m: float) -> dict:
    """The "structure" group's channels from the sensors (``col(name, k)``: column k of a sensor):
    ``rod_stretch`` (B'–C' distance minus L), ``rod_deflection`` (the mid-span point's distance from the
    chord B'–C', + to the left of B'→C'), the supports' displacements."""
    import numpy as np

    bx, by = col(names.SENSOR_ROD_B, 0), col(names.SENSOR_ROD_B, 1)
    mx, my = col(names.SENSOR_ROD_MID, 0), col(names.SENSOR_ROD_MID, 1)
    cx, cy = col(names.SENSOR_ROD_C, 0), col(names.SENSOR_ROD_C, 1)
    dx, dy = cx - bx, cy - by
    d = np.hypot(dx, dy)
    return {"rod_stretch": d - length_m,
            "rod_deflection": (dx * (my - by) - dy * (mx - bx)) / d,
            "frame_x": col(names.SENSOR_FRAME_X), "frame_y": col(names.SENSOR_FRAME_Y),
            "guide_y": col(names.SENSOR_GUIDE_Y)}



def exact_structure_numbers(xml: str, model: mujoco.MjModel) -> str:
    """``xml`` (MuJoCo's writer keeps 6 significant digits) with the structure's numbers written from the compiled
    ``model`` at full precision: every named joint's ``stiffness`` and ``damping``, every named body's inertial
    ``mass`` and ``diaginertia`` (the chain's modes and damping ratios then survive the export exactly)."""
    import re

    def num(v: float) -> str:
        return repr(float(v)).removesuffix(".0")

    for j in range(model.njnt):
        name = model.joint(j).name
        if not name:
            continue
        k = model.jnt_stiffness[j]
        c = model.dof_damping[model.jnt_dofadr[j]]
        for attr, value in (("stiffness", k), ("damping", c)):
            tag = re.compile(r'(<joint\b[^>]*?\bname="' + re.escape(name) + r'"[^>]*?\b' + attr + r'=")[^"]*(")')
            xml = tag.sub(lambda mt, v=value: mt.group(1) + num(v) + mt.group(2), xml, count=1)
    for b in range(1, model.nbody):
        name = model.body(b).name
        if not name:
            continue
        tag = re.compile(r'(<body\b[^>]*?\bname="' + re.escape(name) + r'"[^>]*>\s*<inertial\b[^>]*?\bmass=")[^"]*'
                         r'("[^>]*?\bdiaginertia=")[^"]*(")')
        di = " ".join(num(v) for v in model.body_inertia[b])
        xml = tag.sub(lambda mt, m=model.body_mass[b], d=di: mt.group(1) + num(m) + mt.group(2) + d + mt.group(3),
                      xml, count=1)
    return xml
