"""Winch: the drum at end a of a RopeChain. Split by concept as in MoorDyn: the chain owns the
element and connection arrays, the winch holds the drum's state and settings and acts on the
chain between kernel calls: the rope leaving or entering at element 0 (wind), the links split,
merged, halved or dropped there, and the sub-step loop of a step with the drum turning (step).
No ROS here.

Modes and laws: README.md "Winch"; RopeChain's set_winch, set_payout_rate, drum_rate,
winch_state and its winch attributes (winch_mode, payout_rate, ...) delegate to it.
"""
from __future__ import annotations

import math

import numpy as np

from . import kernels as K


def _tension(name, v, allow_zero):
    """A tension order (N) as a float, None kept; ValueError naming it when not a finite
    positive (allow_zero: non-negative) number."""
    if v is None:
        return None
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise ValueError(f"winch {name}: expected a number (N), got {v!r}") from None
    if not math.isfinite(x) or x < 0.0 or (x == 0.0 and not allow_zero):
        raise ValueError(f"winch {name}: expected a finite {'non-negative' if allow_zero else 'positive'} "
                         f"tension (N), got {v!r}")
    return x


class Winch:
    """The drum at end a: its mode and settings, the pay-out rate now, and the nominal link
    length the chain's element 0 is split / merged around. Every rope has one (the rope file's
    winch: settings); only a fitted one (RopeChain.wound_on_winch) takes orders and turns."""

    MODES = ("speed", "hold", "constant_tension")  # README "Winch": what the drum does in each
    TINY = 1e-3  # element 0 is wound in completely below this fraction of a nominal length
    MIN_ELEMENTS = 4  # heave-in keeps at least this many links (see wind)

    def __init__(self, params, fitted, nominal_element_length):
        """The drum stopped, in the mode and with the settings of the rope file's winch:
        section (order changes them later)."""
        self.params = params
        self.fitted = bool(fitted)
        self.l_nom = float(nominal_element_length or params.nominal_element_length)
        self.payout_rate = 0.0  # the drum's pay-out rate now, m/s (+ out): the order in 'speed'
        w = params.winch.resolved(params.breaking_load, params.winch_max_payout_speed)
        self.mode = w["mode"]
        self.set_tension = w["set_tension"]
        self.recover_tension = w["recover_tension"]
        self.brake_load = w["brake_load"]
        self.gain = w["gain"]
        self.speed_order = 0.0  # the last 'speed' order, m/s

    # ------------------------------------------------------------------ orders
    def set_payout_rate(self, rate_m_per_s):
        """RopeChain.set_payout_rate: the 'speed' order, clamped; returns the notes."""
        r = float(rate_m_per_s)
        if not math.isfinite(r):
            raise ValueError(f"payout rate must be finite, got {rate_m_per_s!r}")
        if not self.fitted:
            raise ValueError("this rope has no winch (use RopeChain.wound_on_winch)")
        p = self.params
        notes = []
        if r > p.winch_max_payout_speed:
            notes.append(f"payout_rate {r:g} m/s clamped to {p.winch_max_payout_speed:g} m/s "
                         f"(winch_max_payout_speed)")
            r = float(p.winch_max_payout_speed)
        elif r < -p.winch_max_heave_speed:
            notes.append(f"payout_rate {r:g} m/s clamped to {-p.winch_max_heave_speed:g} m/s "
                         f"(winch_max_heave_speed)")
            r = -float(p.winch_max_heave_speed)
        self.speed_order = r
        if self.mode == "speed":
            self.payout_rate = r
        return notes

    def order(self, mode=None, *, payout_rate=None, set_tension=None, recover_tension=None,
              brake_load=None):
        """RopeChain.set_winch: checked whole before anything changes; returns the notes."""
        if not self.fitted:
            raise ValueError("this rope has no winch (use RopeChain.wound_on_winch)")
        if mode is not None and mode not in self.MODES:
            raise ValueError(f"winch mode: expected one of {', '.join(self.MODES)}, got {mode!r}")
        ts = _tension("set_tension", set_tension, False)
        tr = _tension("recover_tension", recover_tension, True)
        tb = _tension("brake_load", brake_load, False)
        if payout_rate is not None and not math.isfinite(float(payout_rate)):
            raise ValueError(f"payout rate must be finite, got {payout_rate!r}")
        notes = []
        bl = float(self.params.breaking_load)
        if ts is not None and ts > bl:
            notes.append(f"set_tension {ts:g} N clamped to {bl:g} N (breaking_load)")
            ts = bl
        if tr is not None and tr > bl:
            notes.append(f"recover_tension {tr:g} N clamped to {bl:g} N (breaking_load)")
            tr = bl
        if tb is not None and tb > 2.0 * bl:
            notes.append(f"brake_load {tb:g} N clamped to {2.0 * bl:g} N (2 x breaking_load)")
            tb = 2.0 * bl
        new_ts = self.set_tension if ts is None else ts
        new_tr = self.recover_tension if tr is None else tr
        if new_tr > new_ts:
            raise ValueError(f"winch recover_tension {new_tr:g} N is above set_tension {new_ts:g} N: "
                             f"the lower (recover) tension must not exceed the set (render) tension")
        if payout_rate is not None:
            notes += self.set_payout_rate(payout_rate)
        self.set_tension, self.recover_tension = new_ts, new_tr
        if tb is not None:
            self.brake_load = tb
        if mode is not None and mode != self.mode:
            self.mode = mode
            self.payout_rate = self.speed_order if mode == "speed" else 0.0
        return notes

    # ------------------------------------------------------------------ drum laws
    def drum_rate(self, chain, tension=None):
        """RopeChain.drum_rate: the mode's pay-out rate (m/s) for the drum tension (N; default
        the chain's tension at connection 0)."""
        mode = self.mode
        if mode == "speed":
            return self.speed_order
        if not chain.conn_ok[0]:
            return 0.0
        T = float(chain.tensions[0]) if tension is None else float(tension)
        p, g = self.params, self.gain
        if mode == "hold":
            return min(g * (T - self.brake_load), p.winch_max_payout_speed) if T > self.brake_load else 0.0
        if T > self.set_tension:
            return min(g * (T - self.set_tension), p.winch_max_payout_speed)
        if T < self.recover_tension:
            return -min(g * (self.recover_tension - T), p.winch_max_heave_speed)
        return 0.0

    def auto_rate(self, chain, h):
        """The drum rate for the next sub-step h in 'hold' / 'constant_tension': drum_rate()
        taken implicitly for the drum connection's own response. Paying out dv faster lowers
        the drum tension within the sub-step by about K dv, K = theta h k0 + c0 (the drum
        connection's spring k0 = EA / (L0 / 2) over the theta point and its damper c0 =
        2 zeta_x sqrt(k0 mu L0), kernels._connection_constants); solving v = law(T - K (v -
        v_last)) instead of v = law(T) keeps the loop stable however short the drum link
        (the explicit law gives G k0 h > 2 from about N = 50 up and chatters) and changes no
        steady state: v_n = (law(T_n) + G K v_last) / (1 + G K), a lag of G K h per step."""
        v = self.drum_rate(chain)
        if not chain.conn_ok[0]:
            return v
        p = self.params
        l0 = float(chain.L[0])
        k0 = p.ea / (0.5 * l0)
        c0 = 2.0 * p.damping_ratio_axial * math.sqrt(k0 * p.mass_per_length * l0)
        a = self.gain * (chain.theta * h * k0 + c0)
        return (v + a * self.payout_rate) / (1.0 + a)

    def running(self, chain):
        """True while the drum turns: a pay-out rate is set, the rope is whole at the drum
        and the deployed length is inside its limits in the direction of the rate."""
        dep = float(chain.L.sum())
        return bool(chain.conn_ok[0]) and (
            (self.payout_rate > 0 and dep < self.params.length) or
            (self.payout_rate < 0 and dep > self.params.min_deployed_length))

    def state(self, chain):
        """RopeChain.winch_state: what the drum does now, in words."""
        r = self.payout_rate if self.running(chain) else 0.0
        mode = self.mode
        if mode == "speed":
            return "locked" if r == 0 else ("paying out" if r > 0 else "heaving in")
        if r == 0:
            return "held"
        if mode == "hold":
            return "slipping"
        return "rendering" if r > 0 else "recovering"

    # ------------------------------------------------------------------ stepping
    def step(self, chain, dt, n_sub, h):
        """RopeChain.step with the drum turning: one kernel call per sub-step, the winch
        changes the chain's arrays in between. Returns the kernel status (the chain restored
        to its state before the step unless OK)."""
        info = chain._info
        snap = chain._snapshot()
        rate0 = self.payout_rate
        imp_total = np.zeros((2, 3))
        pos0 = chain.att_pos.copy()
        st = K.OK
        auto = self.mode != "speed"
        for k in range(n_sub):
            chain.att_pos[:] = pos0 + chain.att_vel * (k * h)
            if auto:  # hold / constant tension: the rate from the drum tension of the last evaluation
                self.payout_rate = self.auto_rate(chain, h)
            paying = self.running(chain)  # pay-out active in this sub-step (not at a limit)
            st = chain._kernel(h, 1, self.payout_rate if paying else 0.0, 0.0) & ~K.PARTED
            chain._collect_events(chain.time + k * h)
            if st != K.OK:
                info[0] = k
                chain._restore(snap)
                self.payout_rate = rate0
                break
            imp_total += chain._imp
            self.wind(chain, self.payout_rate * h, h)
        if st == K.OK:
            # tensions at the end of the step: the attachments where they are then, the rope
            # still sliding through the drum
            chain.att_pos[:] = pos0 + chain.att_vel * dt
            st = chain._refresh(chain.time + dt, self.payout_rate if self.running(chain) else 0.0) & ~K.PARTED
            if st != K.OK:
                info[0] = n_sub - 1
                chain._restore(snap)
                self.payout_rate = rate0
                chain.att_pos[:] = pos0
            else:
                chain._mean_end_force[:] = imp_total * (1.0 / dt)
        else:
            chain.att_pos[:] = pos0
        return st

    def wind(self, chain, dl, h):
        """Pay out (dl > 0) or heave in dl metres of rope over the sub-step h at element 0,
        within the deployed length's limits, then split, drop, merge or halve links so that
        element 0 stays within 0.5..1.5 nominal lengths and a short rope keeps enough links."""
        p = self.params
        if not chain.conn_ok[0]:  # the rope has parted at the drum: nothing to wind
            return
        dep = float(chain.L.sum())
        tgt = min(max(dep + dl, p.min_deployed_length), p.length)
        dl = tgt - dep
        tiny = self.TINY * self.l_nom
        can_drop = chain.n_elements >= 2 and bool(chain.conn_ok[1])
        if dl < 0.0:  # element 0 never shrinks below 'tiny' (then it is dropped)
            dl = max(dl, (tiny if can_drop else 0.5 * min(self.l_nom, chain.L[0])) - chain.L[0])
        if dl == 0.0:
            return
        l0 = chain.L[0]
        l_new = l0 + dl
        # rope leaves / enters at the winch end of element 0: its far end stays (a material
        # point) and the element grows / shrinks along its axis at the drum end. The rope
        # slides out of the drum at the pay-out rate: new rope leaves with the drum velocity
        # minus rate * e, and the kernel gives the end connection the same sliding velocity,
        # so the end spring-damper sees no spurious motion.
        e = chain.E[0]
        aft = chain.X[0] - 0.5 * l0 * e
        m0 = p.mass_per_length * l0
        if dl > 0:
            v_new = chain.att_vel[0] - (dl / h) * e
            chain.V[0] = (m0 * chain.V[0] + p.mass_per_length * dl * v_new) / (
                p.mass_per_length * l_new)
        chain.X[0] = aft + 0.5 * l_new * e
        chain.L[0] = l_new
        # slack rope piles up behind the drum: the drum end may not pass the drum
        drum = chain.att_pos[0] + chain.att_vel[0] * h  # attachment at the end of the sub-step
        over = (chain.X[0] + 0.5 * l_new * e - drum) @ e
        if over > 0.0:
            chain.X[0] -= over * e
        while chain.L[0] > 1.5 * self.l_nom:
            self._split0(chain)
        if dl < 0.0 and can_drop:
            self._wound_in(chain, tiny)
        if dl < 0.0:
            self._keep_links(chain, tiny)

    def _wound_in(self, chain, tiny):
        """After heaving in: drop element 0 once wound in completely, or merge it into
        element 1 when it has become short."""
        if chain.L[0] <= tiny * (1.0 + 1e-9):
            # wound in completely: element 1 now hangs from the drum, its front within
            # 'tiny' of it (merging two links at an angle would jump the geometry)
            self._drop0(chain)
        elif (chain.L[0] < 0.5 * self.l_nom and chain.E[0] @ chain.E[1] > 0.98
              and chain.n_elements > self.MIN_ELEMENTS):
            self._merge01(chain)  # nearly straight: merging moves nothing noticeably
        elif chain.L[0] < 0.1 * chain.L[1]:
            # a link much shorter than its neighbour is stiff and light (its axial
            # frequency grows as 1/length): merged even at an angle before it spins up
            self._merge01(chain)

    def _keep_links(self, chain, tiny):
        """A short rope of few long rigid links cannot fold between close bollards (two 9 m
        links hung from bollards 3 m apart lock up and part): heave-in keeps at least
        MIN_ELEMENTS links, none longer than 1.25 times their share."""
        while True:
            j = int(np.argmax(chain.L))
            dep = float(chain.L.sum())
            if chain.L[j] < 4.0 * tiny or (chain.n_elements >= self.MIN_ELEMENTS
                                           and chain.L[j] <= 1.25 * dep / self.MIN_ELEMENTS):
                break
            self._halve(chain, j)

    # ------------------------------------------------------------------ links
    def _halve(self, chain, j):
        """Split element j into two collinear halves moving as the rigid element did: mass,
        momentum and angular momentum unchanged, the new joint whole and unloaded."""
        c = chain
        l, e, x, v, w = c.L[j], c.E[j].copy(), c.X[j].copy(), c.V[j].copy(), c.W[j].copy()
        q = 0.25 * l * e  # centre of each half from the element centre (front half towards end a)
        c.X = np.vstack([c.X[:j], x + q, x - q, c.X[j + 1:]])
        c.E = np.vstack([c.E[:j], e, e, c.E[j + 1:]])
        c.V = np.vstack([c.V[:j], v + np.cross(w, q), v - np.cross(w, q), c.V[j + 1:]])
        c.W = np.vstack([c.W[:j], w, w, c.W[j + 1:]])
        c.L = np.concatenate([c.L[:j], [0.5 * l, 0.5 * l], c.L[j + 1:]])
        c.env = np.insert(c.env, j + 1, c.env[j], axis=0)
        c.conn_ok = np.insert(c.conn_ok, j + 1, 1)
        c.armed = np.insert(c.armed, j + 1, 1)
        c.breaking_load = np.insert(c.breaking_load, j + 1, self.params.breaking_load)
        c.tensions = np.insert(c.tensions, j + 1, 0.0)

    def _drop0(self, chain):
        """Remove element 0 (wound in completely) and the connection behind it; element 1
        hangs from the drum."""
        c = chain
        c.X, c.E, c.V, c.W = c.X[1:], c.E[1:], c.V[1:], c.W[1:]
        c.L = c.L[1:].copy()
        c.X, c.E = c.X.copy(), c.E.copy()
        c.V, c.W = c.V.copy(), c.W.copy()
        c.env = c.env[1:].copy()
        c.conn_ok = np.delete(c.conn_ok, 1)
        c.armed = np.delete(c.armed, 1)
        c.breaking_load = np.delete(c.breaking_load, 1)
        c.tensions = np.delete(c.tensions, 1)

    def _split0(self, chain):
        """Split a nominal length off the far end of element 0 (paid out beyond 1.5 nominal
        lengths), every connection's tension kept."""
        c = chain
        l0, ln = c.L[0], self.l_nom
        e, x0, v0, w0 = c.E[0].copy(), c.X[0].copy(), c.V[0].copy(), c.W[0].copy()
        front = x0 + 0.5 * l0 * e
        c_near = front - 0.5 * (l0 - ln) * e
        c_far = front - (l0 - ln) * e - 0.5 * ln * e
        # under tension (paying out a taut line: render, brake slip) the connections' gaps
        # hold the stretch of the half elements beside them (compliance l_rep / EA, l_rep the
        # two half lengths): redistribute them along e so that every tension is kept, the new
        # inner connection taking the drum tension; splitting with the gaps unchanged would
        # triple the drum connection's tension (its l_rep drops from l0/2 to (l0 - ln)/2)
        T0 = float(c.tensions[0]) if c.conn_ok[0] else 0.0
        T1 = float(c.tensions[1]) if c.conn_ok[1] else 0.0
        if T0 > 0.0 or T1 > 0.0:
            ea = self.params.ea
            back = T1 * 0.5 * (l0 - ln) / ea  # old connection 1: l_rep l0/2 + .. -> ln/2 + ..
            fwd = T0 * 0.5 * l0 / ea - back  # the new inner connection's gap, minus that shift
            if c.att_on[0] and c.conn_ok[0]:  # never past the drum
                fwd = min(fwd, max(0.0, float((c.att_pos[0] - front) @ e)))
            c_far = c_far - back * e
            c_near = c_near + max(fwd, -back) * e
        v_near = v0 + np.cross(w0, c_near - x0)
        v_far = v0 + np.cross(w0, c_far - x0)
        c.X = np.vstack([c_near, c_far, c.X[1:]])
        c.E = np.vstack([e, e, c.E[1:]])
        c.V = np.vstack([v_near, v_far, c.V[1:]])
        c.W = np.vstack([w0, w0, c.W[1:]])
        c.L = np.concatenate([[l0 - ln, ln], c.L[1:]])
        c.env = np.insert(c.env, 1, c.env[0], axis=0)
        c.conn_ok = np.insert(c.conn_ok, 1, 1)
        c.armed = np.insert(c.armed, 1, 1)
        c.breaking_load = np.insert(c.breaking_load, 1, self.params.breaking_load)
        c.tensions = np.insert(c.tensions, 1, c.tensions[0])

    def _merge01(self, chain):
        """Merge elements 0 and 1 into one aimed at the drum, momentum kept."""
        c = chain
        mu = self.params.mass_per_length
        L0, L1 = c.L[0], c.L[1]
        front = c.X[0] + 0.5 * L0 * c.E[0]
        aft = c.X[1] - 0.5 * L1 * c.E[1]
        ln = L0 + L1
        # aim the merged element from the joint with element 2 (kept) at the drum, so that
        # any excess length is axial (slack), never a sideways jump
        d = (c.att_pos[0] if (c.att_on[0] and c.conn_ok[0]) else front) - aft
        nd = np.linalg.norm(d)
        e = d / nd if nd > 1e-9 else c.E[1].copy()
        m0, m1 = mu * L0, mu * L1
        v = (m0 * c.V[0] + m1 * c.V[1]) / (m0 + m1)
        # momentum kept (v); the rotation rate makes the kept joint move on as before, so
        # that its spring-damper sees no jump
        v_aft = c.V[1] + np.cross(c.W[1], aft - c.X[1])
        dv = v_aft - v
        dv -= (dv @ e) * e
        w = -(2.0 / ln) * np.cross(e, dv)
        x = aft + 0.5 * ln * e  # the joint with element 2 stays; any excess is at the drum
        c.X = np.vstack([x, c.X[2:]])
        c.E = np.vstack([e, c.E[2:]])
        c.V = np.vstack([v, c.V[2:]])
        c.W = np.vstack([w, c.W[2:]])
        c.L = np.concatenate([[ln], c.L[2:]])
        env = c.env
        merged = (L0 * env[0] + L1 * env[1]) / ln if np.isfinite(env[:2, c.ENV_DEPTH]).all() else env[1]
        c.env = np.vstack([merged, env[2:]])
        c.conn_ok = np.delete(c.conn_ok, 1)
        c.armed = np.delete(c.armed, 1)
        c.breaking_load = np.delete(c.breaking_load, 1)
        c.tensions = np.delete(c.tensions, 1)
