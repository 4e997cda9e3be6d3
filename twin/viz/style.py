"""Series labels and colours shared by the recording and its blueprint."""

from __future__ import annotations

from twin.config import ACCELEROMETERS, JOINTS
from twin.run import Channel

SIM_COLOUR = (31, 119, 180)
MEAS_COLOUR = (255, 127, 14)
REF_COLOUR = (160, 160, 160)
CHAIN_COLOUR = (148, 103, 189)
JOINT_COLOUR = {"A": (148, 103, 189), "B": (44, 160, 44), "C": (214, 39, 40)}
COLOUR_NAMES = {SIM_COLOUR: "blue", MEAS_COLOUR: "orange", REF_COLOUR: "grey", CHAIN_COLOUR: "purple",
                JOINT_COLOUR["A"]: "purple", JOINT_COLOUR["B"]: "green",
                JOINT_COLOUR["C"]: "red"}


def unit_text(unit: str) -> str:
    return unit.replace("m/s^2", "m/s²") if unit else "-"


def series_label(ch: Channel) -> str:
    """Legend label of a channel: name ('simulated'/'recorded' for accelerations) and unit."""
    unit = unit_text(ch.unit)
    if ch.name.startswith("meas_"):
        return f"{ch.name[5:]} recorded [{unit}]"
    if ch.name.startswith("sim_meas_"):
        return f"{ch.name[9:]} simulated+chain [{unit}]"
    if ch.name.startswith("sim_"):
        return f"{ch.name[4:]} simulated+chain [{unit}]"
    if ch.name.startswith("rec_"):
        return f"{ch.name[4:]} recorded [{unit}]"
    if ch.name in ACCELEROMETERS:
        return f"{ch.name} simulated [{unit}]"
    return f"{ch.name} [{unit}]"


def series_colour(ch: Channel) -> tuple[int, int, int]:
    """Colour of a channel's series: simulated blue, recorded orange, simulated through the
    sensor chain (``sim_*`` of a replay) purple, references grey, joint B green, joint C red."""
    if ch.name in ("omega_ref", "theta_ref"):
        return REF_COLOUR
    if ch.name.startswith("sim_"):
        return CHAIN_COLOUR
    if ch.name.startswith(("meas_", "rec_")) or ch.group == "daq":
        return MEAS_COLOUR
    for j, c in JOINT_COLOUR.items():
        if ch.name.endswith(f"_{j}") or f"_{j}_" in ch.name:
            return c
    return SIM_COLOUR


def series_width(ch: Channel) -> float:
    """Line width of a channel's series [ui points]: the crank speed and angle are drawn wider
    than their grey references, which would otherwise hide them where they agree."""
    return 2.5 if ch.name in ("crank_speed", "crank_angle") else 1.0


#: short names of series in a multi-series plot title
_SHORT = {"crank_speed": "crank", "omega_ref": "reference", "crank_angle": "crank", "theta_ref": "reference",
          "encoder_angle": "sim", "rec_encoder_angle": "rec", "encoder_counts": "rec",
          "sim_encoder_counts": "sim+chain", "motor_command": "rec", "sim_motor_command": "sim+chain",
          **{f"{q}_{j}": j for q in ("fn", "ft", "pen") for j in JOINTS},
          **{f"ecc_{j}_{k}": j for j in JOINTS for k in ("x", "y")}}
_WORDS = {"simulated": "sim", "simulated+chain": "sim+chain", "recorded": "rec"}


def view_title(title: str, chans: list[Channel]) -> str:
    """Plot title naming each shown series and its colour (legends are hidden: a group
    entity's legend would list its hidden series too).

    One series: its label (``AC1 simulated [m/s²]``); several with one unit:
    ``AC1 [m/s²]: sim (blue), rec (orange)``.
    """
    if len(chans) == 1:
        return series_label(chans[0])
    shorts = []
    for c in chans:
        short = _SHORT.get(c.name)
        if short is None:
            short = series_label(c).rsplit(" [", 1)[0]
            if short.startswith(title + " "):
                short = short[len(title) + 1:]
            short = _WORDS.get(short, short)
        shorts.append(f"{short} ({COLOUR_NAMES.get(series_colour(c), '?')})")
    units = {unit_text(c.unit) for c in chans}
    head = f"{title} [{units.pop()}]" if len(units) == 1 else title
    return f"{head}: " + ", ".join(shorts)
