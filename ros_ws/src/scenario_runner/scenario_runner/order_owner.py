"""Who owns each order of a run (ROS-free; the conductor keeps one OrderOwners).

Controls: a vessel's engine, helm and anchor (tug_msgs/VesselCommand on /<vessel>/command) and a
rope's winch (tug_msgs/WinchCommand on /<rope>/winch). Each belongs to the script until somebody
else gives an order for it:

- a scripted event sets only the controls it names; the others keep what the vessel holds,
  whoever ordered that last;
- an order from outside the script (console, instructor page, send_command, an outside
  autopilot) takes the controls it changes: an engine or helm value different from the one held,
  an anchor order (let go, heave up), any winch order. From then on the script's orders for those
  controls yield (announced `manual_order`, and `scripted_order_yielded` at each one not given);
- a hand-back (send_command --hand-back) gives controls back to the script: the value held stays
  until the script's next order for it (`manual_handed_back`);
- a manned vessel (scenario `vessels[].manned: true`) is the crew's from the start: the script
  gives it no orders.

Decisions are taken by the conductor at a step boundary, in the order the messages arrived, and
announced stamped with that step: what the recording shows is what was decided.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

VESSEL_CONTROLS = ("engine", "helm", "anchor")
WINCH = "winch"
# ScenarioEvent kind on /scenario/events asking the conductor to give controls back to the script
# (target: the vessel or rope; detail: the controls, comma-separated, or "all"): send_command --hand-back
HAND_BACK = "hand_back"
ANCHOR_NO_CHANGE, ANCHOR_LET_GO, ANCHOR_HEAVE_UP = 0, 1, 2  # tug_msgs/VesselCommand
ANCHOR_WORDS = {ANCHOR_LET_GO: "let go", ANCHOR_HEAVE_UP: "heave up"}
MANNED = "the crew (vessel manned in the scenario)"
# an outside order differing from the held one by at most this much changes nothing (float noise)
SAME = 1e-9


@dataclasses.dataclass(frozen=True)
class Announcement:
    """A ScenarioEvent the conductor publishes: kind, target (vessel or rope), detail, value (SI)."""
    kind: str  # "manual_order", "manual_handed_back", "scripted_order_yielded", "hand_back_refused"
    target: str
    control: str
    detail: str
    value: float = math.nan


@dataclasses.dataclass
class VesselOrder:
    """One VesselCommand's fields: engine order [-1, 1], helm (steering angle, rad, + port), anchor."""
    engine: float
    helm: float
    anchor: int = ANCHOR_NO_CHANGE


@dataclasses.dataclass(frozen=True)
class WinchOrder:
    """One WinchCommand's fields (m/s, mode, N)."""
    payout_rate: float
    mode: int = 0
    set_tension: float = 0.0
    recover_tension: float = 0.0
    brake_load: float = 0.0


def describe(control: str, value) -> str:
    """A control's order in words, units as people read them."""
    if control == "engine":
        return f"engine {value:+.2f}"
    if control == "helm":
        deg = math.degrees(value)
        side = "port" if deg > 0 else "starboard" if deg < 0 else "midships"
        return f"helm {abs(deg):.1f} deg {side}" if side != "midships" else "helm midships"
    if control == "anchor":
        return f"anchor {ANCHOR_WORDS.get(value, 'no change')}"
    mode = {0: "", 1: ", brake hold", 2: ", constant tension"}.get(value.mode, f", mode {value.mode}")
    return f"winch pay-out {value.payout_rate:+.2f} m/s{mode}"


class OrderOwners:
    """The held orders and their owners of every vessel and winch of a run."""

    def __init__(self, held: Dict[str, Tuple[float, float]], winches: Iterable[str] = (),
                 manned: Iterable[str] = ()):
        """held: vessel -> (engine order, helm rad) it starts with; winches: the ropes with a
        winch; manned: vessels whose every control is the crew's from the start."""
        self.held = {v: VesselOrder(float(e), float(h)) for v, (e, h) in held.items()}
        self.winches = {r: WinchOrder(0.0) for r in winches}
        self.manned = set(manned)
        unknown = self.manned - set(self.held)
        if unknown:
            raise ValueError(f"manned vessel(s) {sorted(unknown)} are not vessels of the run")
        # (target, control) -> who gives its orders; absent: the script
        self.manual: Dict[Tuple[str, str], str] = {(v, c): MANNED for v in self.manned for c in VESSEL_CONTROLS}
        self.last_sent: Dict[str, int] = {}  # target -> the last step the conductor sent it an order

    def owner(self, target: str, control: str) -> str:
        return self.manual.get((target, control), "script")

    def sent(self, target: str, step: int) -> None:
        """The conductor sent an order to target stamped step."""
        self.last_sent[target] = max(step, self.last_sent.get(target, -1))

    # -- the script -------------------------------------------------------------------------
    def script_vessel(self, vessel: str, label: str, engine: Optional[float] = None, helm: Optional[float] = None,
                      anchor: Optional[int] = None) -> Tuple[Optional[VesselOrder], List[Announcement]]:
        """A scripted event's orders for a vessel (None: not named): the command to send (the
        held values for every control it does not set, or that yields), None when nothing of it
        is the script's; and an announcement per control that yields."""
        held = self.held[vessel]
        order = VesselOrder(held.engine, held.helm)
        given, notes = False, []
        for control, value in (("engine", engine), ("helm", helm), ("anchor", anchor)):
            if value is None:
                continue
            who = self.manual.get((vessel, control))
            if who is not None:
                notes.append(Announcement(
                    "scripted_order_yielded", vessel, control,
                    f"{label}: {vessel} {describe(control, value)} not given: the {control} of {vessel} is "
                    f"in manual control ({who})", float(value)))
                continue
            given = True
            if control == "engine":
                order.engine = float(value)
            elif control == "helm":
                order.helm = float(value)
            else:
                order.anchor = int(value)
        if not given:
            return None, notes
        self.held[vessel] = VesselOrder(order.engine, order.helm)
        return order, notes

    def script_winch(self, rope: str, label: str,
                     payout_rate: float) -> Tuple[Optional[WinchOrder], List[Announcement]]:
        """A scripted winch order: the order to send, or None and the announcement if the winch
        is in manual control."""
        who = self.manual.get((rope, WINCH))
        if who is not None:
            return None, [Announcement("scripted_order_yielded", rope, WINCH,
                                       f"{label}: {rope} {describe(WINCH, WinchOrder(payout_rate))} not given: the "
                                       f"winch of {rope} is in manual control ({who})", float(payout_rate))]
        order = WinchOrder(float(payout_rate))
        self.winches[rope] = order
        return order, []

    # -- orders from outside ----------------------------------------------------------------
    def outside_vessel(self, vessel: str, order: VesselOrder, who: str,
                       stamp_step: int) -> Tuple[List[Announcement], bool]:
        """An order somebody else gave a vessel (its stamp's step, stamp_step). Returns the
        announcements of the controls it takes, and whether the conductor must confirm the held
        command (send it again, stamped with the step it decides at): it sent the vessel an order
        since stamp_step, which the vessel may have applied after this one (the later of two
        orders for one step wins)."""
        held = self.held[vessel]
        notes = []
        for control, old, new in (("engine", held.engine, order.engine), ("helm", held.helm, order.helm),
                                  ("anchor", ANCHOR_NO_CHANGE, order.anchor)):
            changed = new != ANCHOR_NO_CHANGE if control == "anchor" else abs(new - old) > SAME
            if changed:
                notes += self._claim(vessel, control, who, f"{describe(control, new)}" + (
                    f" (was {describe(control, old).split(' ', 1)[1]})" if control != "anchor" else ""), float(new))
        self.held[vessel] = VesselOrder(order.engine, order.helm)
        return notes, self.last_sent.get(vessel, -1) >= stamp_step

    def outside_winch(self, rope: str, order: WinchOrder, who: str, stamp_step: int) -> Tuple[List[Announcement], bool]:
        """An order somebody else gave a winch: it takes the winch (as outside_vessel)."""
        self.winches[rope] = order
        notes = self._claim(rope, WINCH, who, describe(WINCH, order), order.payout_rate)
        return notes, self.last_sent.get(rope, -1) >= stamp_step

    def _claim(self, target: str, control: str, who: str, what: str, value: float) -> List[Announcement]:
        """Control taken by who: announced when it was the script's, or another's before."""
        before = self.manual.get((target, control))
        if before == MANNED or before == who:
            return []
        self.manual[(target, control)] = who
        whose = "the script yields" if before is None else f"taken over from {before}; the script still yields"
        return [Announcement("manual_order", target, control,
                             f"{target} {control}: manual order by {who}: {what}; {whose} its {control} orders "
                             f"for {target} (hand back: send_command {target} --hand-back {control})", value)]

    # -- hand-back --------------------------------------------------------------------------
    def hand_back(self, target: str, controls: Sequence[str], who: str) -> List[Announcement]:
        """Give controls of target (vessel or winch rope) back to the script; ["all"] or []: every
        control in manual control. Announces each one handed back (or why not)."""
        if target in self.manned:
            return [Announcement("hand_back_refused", target, "",
                                 f"{target} is manned (scenario): the script gives it no orders, nothing to hand "
                                 f"back to (asked by {who})")]
        mine = [c for (t, c) in self.manual if t == target]
        wanted = mine if not controls or "all" in controls else list(controls)
        notes = []
        for control in wanted:
            was = self.manual.pop((target, control), None)
            if was is None:
                notes.append(Announcement("hand_back_refused", target, control,
                                          f"{target} {control}: not in manual control (asked by {who})"))
                continue
            value = (self.winches[target] if control == WINCH else
                     getattr(self.held[target], control) if control != "anchor" else ANCHOR_NO_CHANGE)
            kept = "" if control == "anchor" else f"; {describe(control, value)} holds until the script's next order"
            notes.append(Announcement("manual_handed_back", target, control,
                                      f"{target} {control}: handed back to the script by {who} (was manual: "
                                      f"{was}){kept}"))
        if not wanted:
            notes.append(Announcement("hand_back_refused", target, "",
                                      f"{target}: nothing in manual control to hand back (asked by {who})"))
        return notes

    def confirmation(self, target: str):
        """What to send again to confirm a target's held orders: a VesselOrder (anchor unchanged)
        or a WinchOrder."""
        if target in self.winches:
            return self.winches[target]
        held = self.held[target]
        return VesselOrder(held.engine, held.helm)
