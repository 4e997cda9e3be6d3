"""Defaults of the bench configuration, read from the base model ``mjcf/bench.xml``.

The base MJCF model is the one place where the numbers it shares with the configuration are
written (each with its source in a comment there): Table 1 masses, centres of mass, inertias
and lengths, the pin and bushing sizes, the bushing friction law (geom user data), the guide
friction, gravity and the vertical axis, d_off, the crank PID gains, the accelerometer mounts,
the timestep and the MuJoCo solver numerics. :mod:`twin.config` takes its defaults from
:func:`defaults`, so the MuJoCo engine, the reference engine and every other user of the
configuration see the XML's values; the builder writes the configuration back into the spec,
an identity for the defaults.

Plain :mod:`xml.etree` (no MuJoCo import: the reference engine and the configuration must not
need it), with the MJCF rules this file uses: attributes come from the element, else from its
default class (``class``, else the nearest ancestor body's ``childclass``, else ``main``) and
that class's parents, else MuJoCo's documented default. The file is parsed once per path
(cached). A missing file or an unreadable value raises :class:`~twin.errors.ModelError` naming
the file, the element and the attribute.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from twin import names
from twin.errors import ModelError

#: MuJoCo's own defaults of the attributes read here (MJCF reference), used when neither the
#: element nor its default class sets them
_MUJOCO_DEFAULTS: dict[tuple[str, str], str] = {
    ("option", "timestep"): "0.002",
    ("option", "integrator"): "Euler",
    ("option", "solver"): "Newton",
    ("option", "iterations"): "100",
    ("option", "tolerance"): "1e-8",
    ("option", "gravity"): "0 0 -9.81",
    ("geom", "pos"): "0 0 0",
    ("site", "pos"): "0 0 0",
    ("site", "quat"): "1 0 0 0",
    ("body", "pos"): "0 0 0",
    ("inertial", "pos"): "0 0 0",
    ("joint", "frictionloss"): "0",
    ("joint", "solreffriction"): "0.02 1",
    ("equality", "solref"): "0.02 1",
    ("equality", "solimp"): "0.9 0.95 0.001 0.5 2",
    ("pid", "kv"): "0",
    ("pid", "ki"): "0",
    ("pid", "imax"): "0",
    ("size", "nuser_geom"): "0",
}
#: element tag -> the tag of its settings in <default> (MJCF: every equality type uses <equality>)
_DEFAULT_TAG = {"connect": "equality", "weld": "equality"}
#: sensitive axis of an accelerometer site (its x axis) in its body frame, by direction
_AXES = {(1, 0): "+x", (-1, 0): "-x", (0, 1): "+y", (0, -1): "-y"}


@dataclass(frozen=True)
class BodyDefaults:
    """One body of S003 Table 1 as the base model gives it.

    Attributes:
        mass_kg: ``<inertial mass>``.
        length_m: crank: pin B's x in the crank frame; rod: bushing C's x in the rod frame;
            slider: twice the half length of the ``slider_block`` geom [m].
        x_g_m: ``<inertial pos>`` x [m].
        inertia_kgm2: ``<inertial diaginertia>`` z (about the crank axis) [kg m²].
    """

    mass_kg: float
    length_m: float
    x_g_m: float
    inertia_kgm2: float


@dataclass(frozen=True)
class AccelDefaults:
    """Mount of one accelerometer site: parent body, (x, y) in the body frame (slider: from
    C', i.e. minus d_off), sensitive axis (the site's x axis)."""

    body: str
    position_m: tuple[float, float]
    axis: str


@dataclass(frozen=True)
class ModelDefaults:
    """Every configuration default the base model holds (field names: the configuration's)."""

    path: str
    crank: BodyDefaults
    rod: BodyDefaults
    slider: BodyDefaults
    pin_diameter_m: float
    bushing_length_m: float
    orientation: str
    gravity_mps2: float
    d_off_m: float
    guide_friction_n: float
    mu0: float
    v0_mps: float
    v1_mps: float
    integrator: str
    solver: str
    iterations: int
    tolerance: float
    equality_solref: tuple[float, ...]
    equality_solimp: tuple[float, ...]
    guide_solreffriction: tuple[float, ...]
    kp: float
    kv: float
    ki: float
    imax: float
    accelerometers: tuple[tuple[str, AccelDefaults], ...]
    timestep_s: float
    nuser_geom: int
    bushing_userdata: tuple[float, ...]

    def accelerometer(self, name: str) -> AccelDefaults:
        """Mount of accelerometer ``name`` (AC1..AC6)."""
        return dict(self.accelerometers)[name]


class _Reader:
    """Attribute lookup with MJCF default classes on one parsed file."""

    def __init__(self, path: Path):
        self.path = path
        try:
            self.root = ET.parse(path).getroot()
        except FileNotFoundError:
            raise ModelError(f"cannot load base model {path}: the file is missing (a broken installation: "
                             "reinstall twin)") from None
        except (OSError, ET.ParseError) as err:
            raise ModelError(f"cannot load base model {path}: {err}") from None
        if self.root.tag != "mujoco":
            raise ModelError(f"{path}: the root element is <{self.root.tag}>, not <mujoco>")
        self.parent = {c: p for p in self.root.iter() for c in p}
        # class name -> (its <default> element, the parent class name)
        self.classes: dict[str, tuple[ET.Element, str | None]] = {}
        for top in self.root.findall("default"):
            self._collect(top, None)

    def _collect(self, elem: ET.Element, parent: str | None) -> None:
        name = elem.get("class", "main")  # the top-level <default> is class "main"
        self.classes[name] = (elem, parent)
        for sub in elem.findall("default"):
            self._collect(sub, name)

    def where(self, elem: ET.Element) -> str:
        return f"{self.path.name}: <{elem.tag}{' name=' + repr(elem.get('name')) if elem.get('name') else ''}>"

    def _class_of(self, elem: ET.Element) -> str:
        if elem.get("class"):
            return elem.get("class")
        p = self.parent.get(elem)
        while p is not None:
            if p.tag == "body" and p.get("childclass"):
                return p.get("childclass")
            p = self.parent.get(p)
        return "main"

    def raw(self, elem: ET.Element, attr: str, required: bool = True) -> str | None:
        if attr in elem.attrib:
            return elem.get(attr)
        tag = _DEFAULT_TAG.get(elem.tag, elem.tag)
        cls = self._class_of(elem) if elem.tag not in ("option", "size", "body", "inertial") else None
        if cls is not None and cls not in self.classes and cls != "main":
            raise ModelError(f"{self.where(elem)} uses the unknown default class {cls!r}")
        while cls is not None and cls in self.classes:
            d, parent = self.classes[cls]
            sub = d.find(tag)
            if sub is not None and attr in sub.attrib:
                return sub.get(attr)
            cls = parent
        if (elem.tag, attr) in _MUJOCO_DEFAULTS or (tag, attr) in _MUJOCO_DEFAULTS:
            return _MUJOCO_DEFAULTS.get((elem.tag, attr), _MUJOCO_DEFAULTS.get((tag, attr)))
        if required:
            raise ModelError(f"{self.where(elem)} has no {attr!r} (none in its default class either)")
        return None

    def numbers(self, elem: ET.Element, attr: str, n: int | None = None) -> tuple[float, ...]:
        text = self.raw(elem, attr)
        try:
            values = tuple(float(v) for v in text.split())
        except ValueError:
            raise ModelError(f"{self.where(elem)}: {attr}={text!r} is not a list of numbers") from None
        if not values or not all(math.isfinite(v) for v in values) or (n is not None and len(values) != n):
            want = f"{n} finite numbers" if n is not None else "finite numbers"
            raise ModelError(f"{self.where(elem)}: {attr}={text!r} must hold {want}")
        return values

    def number(self, elem: ET.Element, attr: str) -> float:
        return self.numbers(elem, attr, 1)[0]

    def integer(self, elem: ET.Element, attr: str) -> int:
        text = self.raw(elem, attr)
        try:
            return int(text)
        except ValueError:
            raise ModelError(f"{self.where(elem)}: {attr}={text!r} is not an integer") from None

    def find(self, xpath: str, what: str) -> ET.Element:
        elem = self.root.find(xpath)
        if elem is None:
            raise ModelError(f"{self.path.name}: no {what} ({xpath})")
        return elem

    def named(self, tag: str, name: str) -> ET.Element:
        return self.find(f".//{tag}[@name='{name}']", f"<{tag} name={name!r}>")


def _same(r: _Reader, value: float, others: list[tuple[ET.Element, float]], what: str) -> float:
    """``value``, checked against the other places the file writes the same number."""
    for elem, v in others:
        if not math.isclose(v, value, rel_tol=1e-12, abs_tol=1e-15):
            raise ModelError(f"{r.where(elem)}: {what} is {v!r} here but {value!r} elsewhere in the file")
    return value


def _body(r: _Reader, name: str, length: float) -> BodyDefaults:
    inertial = r.find(f".//body[@name='{name}']/inertial", f"<inertial> of body {name!r}")
    if "fullinertia" in inertial.attrib:
        raise ModelError(f"{r.where(inertial)} of {name!r}: use diaginertia (planar bodies)")
    return BodyDefaults(mass_kg=r.number(inertial, "mass"), length_m=length,
                        x_g_m=r.numbers(inertial, "pos", 3)[0], inertia_kgm2=r.numbers(inertial, "diaginertia", 3)[2])


def _axis(r: _Reader, site: ET.Element) -> str:
    for attr in ("axisangle", "euler", "xyaxes", "zaxis"):
        if attr in site.attrib:
            raise ModelError(f"{r.where(site)}: give the orientation as quat (read by twin.model_xml), not {attr}")
    w, x, y, z = r.numbers(site, "quat", 4)
    s = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / s, x / s, y / s, z / s
    ax = (1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y))  # rotated x axis
    for (cx, cy), axis in _AXES.items():
        if abs(ax[0] - cx) < 1e-6 and abs(ax[1] - cy) < 1e-6 and abs(ax[2]) < 1e-6:
            return axis
    raise ModelError(f"{r.where(site)}: the sensitive (x) axis {ax} is not one of +x, -x, +y, -y of its body")


def read_defaults(path: Path) -> ModelDefaults:
    """Parse ``path`` (uncached; see :func:`defaults`)."""
    r = _Reader(Path(path))
    opt = r.find("option", "<option>")
    size = r.find("size", "<size>")

    # geometry: lengths and the pin/bushing
    pin_b, pin_c = r.named("geom", names.pin("B")), r.named("geom", names.pin("C"))
    bush_b, bush_c = r.named("geom", names.bushing("B")), r.named("geom", names.bushing("C"))
    pin_a, bush_a = r.named("geom", names.pin("A")), r.named("geom", names.bushing("A"))  # crank journal, frame bore
    rod_body = r.named("body", names.ROD)
    crank_len = _same(r, r.numbers(pin_b, "pos", 3)[0],
                      [(r.named("site", names.pin("B")), r.numbers(r.named("site", names.pin("B")), "pos", 3)[0]),
                       (rod_body, r.numbers(rod_body, "pos", 3)[0])], "the crank length (x of pin B)")
    rod_len = _same(r, r.numbers(bush_c, "pos", 3)[0],
                    [(e, r.numbers(e, "pos", 3)[0]) for e in (r.named("site", names.bushing("C")),
                                                              r.named("geom", names.bushing_ring("C")))],
                    "the rod length (x of bushing C)")
    slider_len = 2 * r.numbers(r.named("geom", names.SLIDER_BLOCK), "size", 3)[0]
    pin_r, half = r.numbers(pin_b, "size", 2)
    for g in (pin_a, bush_a, pin_c, bush_b, bush_c):  # the base model is ideal: bore radius = pin radius
        _same(r, pin_r, [(g, r.numbers(g, "size", 2)[0])], "the pin radius")
        _same(r, half, [(g, r.numbers(g, "size", 2)[1])], "the pin/bushing half length")

    # d_off: C' above the slider's reference point
    d_off = _same(r, r.numbers(pin_c, "pos", 3)[1],
                  [(r.named("site", names.pin("C")), r.numbers(r.named("site", names.pin("C")), "pos", 3)[1]),
                   (r.find(f".//body[@name='{names.SLIDER}']/inertial", "slider inertial"),
                    r.numbers(r.find(f".//body[@name='{names.SLIDER}']/inertial", "slider inertial"), "pos", 3)[1])],
                  "d_off (y of pin C)")

    # gravity -> vertical axis and magnitude
    g = r.numbers(opt, "gravity", 3)
    nonzero = [i for i, v in enumerate(g) if v != 0]
    if len(nonzero) != 1 or g[nonzero[0]] > 0:
        raise ModelError(f"{r.where(opt)}: gravity={' '.join(f'{v:g}' for v in g)} must point along minus one "
                         "bench axis (the configuration's mechanism.orientation)")

    # the bushing's friction law (geom user data, layout twin.names.BORE_USERDATA_FIELDS)
    nuser = r.integer(size, "nuser_geom")
    if nuser != len(names.BORE_USERDATA_FIELDS):
        raise ModelError(f"{r.where(size)}: nuser_geom={nuser} but the bore user data layout has "
                         f"{len(names.BORE_USERDATA_FIELDS)} fields {names.BORE_USERDATA_FIELDS} (twin.names)")
    user = r.numbers(bush_b, "user", nuser)
    _same(r, 0.0, [(g, max(abs(a - b) for a, b in zip(user, r.numbers(g, "user", nuser)))) for g in (bush_a, bush_c)],
          "the bushing user data (difference to bushing B)")
    fields = names.read_bore_userdata(user)
    if fields["marker"] != names.BORE_MAGIC:
        raise ModelError(f"{r.where(bush_b)}: user data marker {fields['marker']:g} is not {names.BORE_MAGIC:g}")

    slide = r.named("joint", names.SLIDER_SLIDE)
    connect = r.find(f".//equality/connect[@name='{names.JOINT_C_CONNECT}']", f"connect {names.JOINT_C_CONNECT!r}")
    pid = r.find(f".//actuator/pid[@name='{names.CRANK_PID}']", f"<pid name={names.CRANK_PID!r}>")

    accels = []
    for name in names.ACCEL_SENSORS:
        site = r.named("site", name)
        body = r.parent[site]
        if body.tag != "body" or body.get("name") not in (names.ROD, names.SLIDER):
            raise ModelError(f"{r.where(site)} must sit in body {names.ROD!r} or {names.SLIDER!r}")
        x, y, _ = r.numbers(site, "pos", 3)
        if body.get("name") == names.SLIDER:
            y -= d_off
        accels.append((name, AccelDefaults(body.get("name"), (x, y), _axis(r, site))))

    return ModelDefaults(
        path=str(path),
        crank=_body(r, names.CRANK, crank_len), rod=_body(r, names.ROD, rod_len), slider=_body(r, names.SLIDER, slider_len),
        pin_diameter_m=2 * pin_r, bushing_length_m=2 * half,
        orientation="xyz"[nonzero[0]], gravity_mps2=-g[nonzero[0]], d_off_m=d_off,
        guide_friction_n=r.number(slide, "frictionloss"),
        mu0=fields["mu0"], v0_mps=fields["v0"], v1_mps=fields["v1"],
        integrator=r.raw(opt, "integrator"), solver=r.raw(opt, "solver"), iterations=r.integer(opt, "iterations"),
        tolerance=r.number(opt, "tolerance"),
        equality_solref=r.numbers(connect, "solref", 2), equality_solimp=r.numbers(connect, "solimp", 5),
        guide_solreffriction=r.numbers(slide, "solreffriction", 2),
        kp=r.number(pid, "kp"), kv=r.number(pid, "kv"), ki=r.number(pid, "ki"), imax=r.number(pid, "imax"),
        accelerometers=tuple(accels),
        timestep_s=r.number(opt, "timestep"),
        nuser_geom=nuser, bushing_userdata=tuple(user),
    )


@lru_cache(maxsize=4)
def _cached(path: str) -> ModelDefaults:
    return read_defaults(Path(path))


def defaults(path: Path | str | None = None) -> ModelDefaults:
    """Configuration defaults of the packaged base model (``twin.names.BASE_XML``) or of
    ``path``; parsed once per path."""
    return _cached(str(path if path is not None else names.BASE_XML))
