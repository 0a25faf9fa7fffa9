"""Rigs for the blind test of `epa diagnose`: the paper's plant perturbed within its printed
digits, with effects written from the physics of each phenomenon in forms that are NOT the ones
the diagnosis fits (src/plant/effects.*). Nothing here imports or mirrors the project's code; the
truth forms were fixed before the diagnosis was changed, and are not to be changed to make it pass.

How each truth form differs from the fitted one:

  friction      fitted: Coulomb against the model's mechanical speed while sliding, holding the
                drive up to a breakaway level while sticking; a force through the model's slow
                pole, the valve's flow still reaching B.
                truth: Karnopp with a Stribeck curve and viscous term on the piston's velocity,
                which freezes the piston while stuck; and LuGre bristles (presliding, no hard stick).
                Shared: how a force enters the printed model (through its slow pole, not B), a
                physical choice both sides make; the friction laws differ.
  position      fitted: a gain slope along the stroke, a chamber slope mirrored per direction and
                a quadratic curvature, at the mean of the last few positions; a gain that holds
                beside them is their level.
                truth: chamber compressibility, gain ~ 1/(dead volume + chamber length), mirrored
                per direction; and a cosine dip of the gain around mid-stroke.
  spool         fitted: one lag, or two real lags in series (critically or over-damped).
                truth: second-order spool (natural frequency, damping 0.7-0.8: under-damped);
                a slew-rate-limited spool.
  delay         fitted: whole samples.     truth: fractional delays, and a line delay with a lag.
  flow          fitted: a ceiling per direction through a knee s / (1 + |s/c|^n)^(1/n)
                (n from 1.5, soft, to 64, hard).
                truth: soft (tanh) saturation with a different knee each way; hard limits that
                differ per direction.
  supply        fitted: one gain ratio.    truth: flow ~ sqrt of the pressure drop, rod-side area
                making the two directions differ; a supply that sags during the run.
  break points  fitted: both points shifted.  truth: shifted points with a soft (rounded) edge.
  sensor        fitted: rounding to a step.   truth: a 10-bit and an 8-bit ADC over the span
                after the noise (dither); an encoder that moves only after a full step (hysteresis).
  outside the vocabulary: a periodic load force; a sensor offset that drifts; outlier spikes.
"""
import math

TS = 0.005
MM_PER_V = 50.0
STROKE_MM = 500.0
NOISE_MM = 0.1

# The paper's printed model (eq 9-10) and controller (eq 12-13).
A_PRIME = (0.0906, -0.5204)         # A = (1 - q)(1 + a1 q + a2 q^2)
B = (1.024, -2.046, 1.029)          # q^-1 .. q^-3
DZ = dict(m_r=1.7627, m_l=1.0707, b_r=1.232, b_l=-1.722)
F = (1.0, -1.778, 0.7828)
G = (-0.1734, 0.577, -0.3958)
LC_MM = 5.0
VALVE_LIMIT_V = 5.0


def perturbed_nominal(rng):
    """The printed numbers, each moved by up to half a unit of its last printed digit."""
    def half(d):
        return rng.uniform(-0.5, 0.5) * 10.0 ** -d
    a = (A_PRIME[0] + half(4), A_PRIME[1] + half(4))
    b = tuple(x + half(3) for x in B)
    dz = dict(m_r=DZ["m_r"] + half(4), m_l=DZ["m_l"] + half(4), b_r=DZ["b_r"] + half(3), b_l=DZ["b_l"] + half(3))
    return dict(a=a, b=b, dz=dz)


# --- truth effects, each a small class with the state of its physics -------------------------

class NoSpool:
    def __call__(self, u):
        return u


class SecondOrderSpool:
    """Spool position x: x'' = w^2 (u - x) - 2 zeta w x' (semi-implicit Euler, 10 substeps)."""
    def __init__(self, freq_hz, zeta):
        self.w, self.z, self.x, self.v = 2 * math.pi * freq_hz, zeta, 0.0, 0.0

    def __call__(self, u):
        h = TS / 10
        for _ in range(10):
            self.v += h * (self.w * self.w * (u - self.x) - 2 * self.z * self.w * self.v)
            self.x += h * self.v
        return self.x


class SlewLimitedSpool:
    def __init__(self, rate_v_per_s):
        self.step, self.x = rate_v_per_s * TS, 0.0

    def __call__(self, u):
        self.x += max(-self.step, min(self.step, u - self.x))
        return self.x


class FractionalDelay:
    """Delay of `samples` (not whole), interpolated between the two commands around it; an
    optional lag after it (a pneumatic line: transport, then filling)."""
    def __init__(self, samples, lag_s=0.0):
        self.n, self.f = int(samples), samples - int(samples)
        self.past = [0.0] * (self.n + 2)
        self.alpha = 1.0 - math.exp(-TS / lag_s) if lag_s > 0 else 1.0
        self.y = 0.0

    def __call__(self, u):
        self.past = [u] + self.past[:-1]
        d = (1 - self.f) * self.past[self.n] + self.f * self.past[self.n + 1]
        self.y += self.alpha * (d - self.y)
        return self.y


def dead_zone(u, dz, soft_v=0.0, shift_r=0.0, shift_l=0.0):
    """The valve's overlap: slopes m_r, m_l beyond b_r, b_l; with soft_v > 0 the edges are rounded
    over soft_v volts (a quadratic blend: a spool whose lands are not sharp)."""
    b_r, b_l = dz["b_r"] + shift_r, dz["b_l"] + shift_l
    if soft_v <= 0:
        if u > b_r:
            return dz["m_r"] * (u - b_r)
        if u < b_l:
            return dz["m_l"] * (u - b_l)
        return 0.0
    h = soft_v / 2
    if u > b_r + h:
        return dz["m_r"] * (u - b_r)
    if u > b_r - h:
        return dz["m_r"] * (u - b_r + h) ** 2 / (4 * h)
    if u < b_l - h:
        return dz["m_l"] * (u - b_l)
    if u < b_l + h:
        return -dz["m_l"] * (b_l + h - u) ** 2 / (4 * h)
    return 0.0


class Rig:
    """One rig: the perturbed nominal with truth effects. step(u) applies a valve command for one
    sample and returns the measured position (mm) of the next."""

    def __init__(self, nominal, effects, rng, x0_mm=250.0):
        self.n, self.e, self.rng = nominal, effects, rng
        self.x = x0_mm
        self.w1 = self.w2 = 0.0                 # increments of position (sensor V per sample)
        self.ud = [0.0, 0.0, 0.0]               # drive history u_d(k-1..k-3)
        a1, a2 = nominal["a"]
        self.slow_pole = (-a1 + math.sqrt(a1 * a1 - 4 * a2)) / 2       # the positive root of z^2 + a1 z + a2
        self.speed_per_v = sum(nominal["b"]) / (1 + a1 + a2) * MM_PER_V / TS  # steady mm/s per V of drive
        self.v_mech = self.v_friction = 0.0
        self.recent = [x0_mm] * 8  # the model's last positions: their mean is where the piston is
        self.stuck = True
        self.z = 0.0                            # LuGre bristle deflection, mm
        self.t = 0.0
        self.spool = effects.get("spool", NoSpool())
        self.enc = x0_mm

    def piston_mm(self):
        """Where the piston is, for effects that depend on it: the printed B swings the model's
        position at the Nyquist frequency with every change of the drive, which the mean over 8
        samples removes (fed back, that swing would feed on itself)."""
        return sum(self.recent) / len(self.recent)

    def drive(self, u):
        e, dz = self.e, self.n["dz"]
        s = self.spool(u)
        ud = dead_zone(s, dz, e.get("soft_edge_v", 0.0), e.get("shift_r", 0.0), e.get("shift_l", 0.0))
        if "supply_bar" in e:  # flow ~ sqrt(supply - exhaust); the rod side fills a smaller area
            p0, p = 6.0, e["supply_bar"] - e.get("sag_bar_per_s", 0.0) * self.t
            r = math.sqrt(max(0.05, (p - 1.0) / (p0 - 1.0)))
            ud *= r * (1.0 if ud >= 0 else e.get("retract_factor", 1.0))
        if "tanh_knee" in e:
            k = e["tanh_knee"][0] if ud >= 0 else e["tanh_knee"][1]
            ud = k * math.tanh(ud / k)
        if "hard_limit" in e:
            ud = min(e["hard_limit"][0], max(-e["hard_limit"][1], ud))
        if "compress_mm" in e:  # the driving chamber's length: x extending, stroke - x retracting
            x0 = e["compress_mm"]
            length = self.piston_mm() if ud >= 0 else STROKE_MM - self.piston_mm()
            ud *= (x0 + STROKE_MM / 2) / (x0 + max(0.0, length))
        if "cos_dip" in e:  # the gain dips around mid-stroke, back to nominal at the ends
            ud *= 1.0 - e["cos_dip"] * 0.5 * (1.0 + math.cos(2 * math.pi * (self.piston_mm() - STROKE_MM / 2) / STROKE_MM))
        if "load_v" in e:  # a periodic load force, in drive volts
            ud += e["load_v"] * math.sin(2 * math.pi * e["load_hz"] * self.t)
        return ud

    def friction(self, ud):
        """The friction force in drive volts; None while the piston is stuck."""
        e = self.e
        # The velocity friction sees: the drive's steady speed through the slow pole of A' (the
        # printed B swings each sample's displacement with every change of the drive; no piston does).
        v = self.v_mech
        if "karnopp" in e:
            fs, fc, vs, visc = e["karnopp"]
            if self.stuck:
                if abs(ud) > fs:
                    self.stuck = False
                    return math.copysign(fs, ud)
                return None
            if abs(v) < 2.0 and abs(ud) <= fs:
                self.stuck = True
                return None
            direction = v if abs(v) >= 2.0 else ud
            return math.copysign(fc + (fs - fc) * math.exp(-(v / vs) ** 2) + visc * abs(v), direction)
        if "lugre" in e:
            fs, fc, vs, sigma0 = e["lugre"]
            g = fc + (fs - fc) * math.exp(-(v / vs) ** 2)
            if abs(v) > 1e-9:  # exact for a constant velocity over the sample
                zs = math.copysign(g / sigma0, v)
                self.z = zs + (self.z - zs) * math.exp(-sigma0 * abs(v) * TS / g)
            return sigma0 * self.z + 0.001 * v
        return 0.0

    def step(self, u):
        """The valve's drive goes through the printed model; friction acts on the piston, through
        the model's slow pole and steady speed (not through B, whose swing answers the valve's
        flow changes, not a force on the mass)."""
        a1, a2 = self.n["a"]
        b1, b2, b3 = self.n["b"]
        ud = self.drive(u)
        f = self.friction(ud)
        if f is None:  # stuck: the piston and its flow states are at rest
            self.w1 = self.w2 = self.v_mech = self.v_friction = 0.0
            self.ud = [0.0, 0.0, 0.0]
        else:
            p = self.slow_pole
            self.ud = [ud] + self.ud[:2]
            w = -a1 * self.w1 - a2 * self.w2 + b1 * self.ud[0] + b2 * self.ud[1] + b3 * self.ud[2]
            self.w2, self.w1 = self.w1, w
            self.v_friction = p * self.v_friction - (1 - p) * self.speed_per_v * f
            self.v_mech = p * self.v_mech + (1 - p) * self.speed_per_v * (ud - f)
            self.x += MM_PER_V * w + self.v_friction * TS
        if self.x < 0.0 or self.x > STROKE_MM:  # end stops
            self.x = min(STROKE_MM, max(0.0, self.x))
            self.w1 = self.w2 = self.v_mech = self.v_friction = 0.0
            self.ud = [0.0, 0.0, 0.0]
        self.recent = [self.x] + self.recent[:-1]
        self.t += TS
        return self.measure()

    def measure(self):
        e = self.e
        y = self.x + self.rng.gauss(0.0, NOISE_MM)
        if "drift_mm_s" in e:
            y += e["drift_mm_s"] * self.t
        if "spike_prob" in e and self.rng.random() < e["spike_prob"]:
            y += self.rng.choice((-1, 1)) * self.rng.uniform(5.0, 20.0)
        if "adc_bits" in e:
            q = STROKE_MM / (2 ** e["adc_bits"] - 1)
            y = q * round(y / q)
        if "encoder_mm" in e:
            s = e["encoder_mm"]
            while y - self.enc >= s:
                self.enc += s
            while self.enc - y >= s:
                self.enc -= s
            y = self.enc
        return y


# --- what a commissioning engineer records ---------------------------------------------------

class Controller:
    """The paper's pole placement, F uc = G (r - y) in sensor volts, with FF-IDZ or NG-IDZ."""
    def __init__(self, kind):
        self.kind, self.u1, self.u2, self.e1, self.e2 = kind, 0.0, 0.0, 0.0, 0.0

    def __call__(self, r_mm, y_mm):
        e = (r_mm - y_mm) / MM_PER_V
        uc = -F[1] * self.u1 - F[2] * self.u2 + G[0] * e + G[1] * self.e1 + G[2] * self.e2
        self.u2, self.u1, self.e2, self.e1 = self.u1, uc, self.e1, e
        if self.kind == "pp-ffidz":
            lc = 1.0 if abs(r_mm - y_mm) > LC_MM else 0.0
            ff = uc / DZ["m_r"] + DZ["b_r"] if e > 0 else uc / DZ["m_l"] + DZ["b_l"]
            u = uc + lc * ff
        else:  # pp-ngidz
            u = uc / DZ["m_r"] + DZ["b_r"] if uc > 0 else uc / DZ["m_l"] + DZ["b_l"] if uc < 0 else 0.0
        return max(-VALVE_LIMIT_V, min(VALVE_LIMIT_V, u)), uc


def closed_loop_run(rig, kind, seconds, rng):
    ctl = Controller(kind)
    y, r = rig.measure(), rig.x
    rows, next_change = [], 0
    for k in range(int(seconds / TS)):
        if k == next_change:
            size = rng.uniform(25.0, 150.0)  # the printed model swings ~20 % past a large step
            direction = -1 if r > 300 else 1 if r < 200 else rng.choice((-1, 1))
            r = min(400.0, max(100.0, r + direction * size))
            next_change = k + int(rng.uniform(2.0, 3.5) / TS)
        u, uc = ctl(r, y)
        rows.append((k * TS, r, y, u, uc))
        y = rig.step(u)
    return kind, rows


def open_loop_run(rig, kind, seconds, rng):
    """ramps: slow triangles through the dead band, each way in turn; pulses: 0.2-1.5 V beyond
    the break points for 0.05-0.25 s with rests of 0.2-0.6 s. Each excursion is sized from the
    nominal speed so that it stays clear of the ends, as an engineer guards a rig's cushions."""
    speed = 122.8  # mm/s per V of drive, from the printed B(1)/A'(1)
    y, rows = rig.measure(), []
    n = int(seconds / TS)
    k = 0

    def emit(command):
        nonlocal y, k
        if k < n:
            rows.append((k * TS, None, y, command, None))
            y = rig.step(command)
            k += 1

    while k < n:
        side = -1 if y > 300 else 1 if y < 200 else rng.choice((-1, 1))
        room = (420.0 - y) if side > 0 else (y - 80.0)
        m, b = (DZ["m_r"], DZ["b_r"]) if side > 0 else (DZ["m_l"], -DZ["b_l"])
        if kind == "ramps":
            excess, half = rng.uniform(0.5, 1.0), rng.uniform(0.8, 1.4)
            top = b + excess
            travel = speed * m * excess * excess / top * half  # mean drive over the time above b
            if travel > room:
                excess *= max(0.2, room / travel)
                top = b + excess
            ramp = int(half / TS)
            for i in list(range(ramp)) + list(range(ramp, -1, -1)):
                emit(side * top * i / ramp)
            for _ in range(int(rng.uniform(0.3, 0.8) / TS)):
                emit(0.0)
        else:
            excess, duration = rng.uniform(0.2, 1.5), rng.uniform(0.05, 0.25)
            travel = speed * m * excess * duration + 51.0 * m * excess  # the run and the printed model's swing
            if travel > room:
                duration *= max(0.1, (room - 51.0 * m * excess) / (travel - 51.0 * m * excess))
            for _ in range(max(1, int(duration / TS))):
                emit(side * (b + excess))
            for _ in range(int(rng.uniform(0.2, 0.6) / TS)):
                emit(0.0)
    return "open-loop", rows


def write_run(path, controller, rows):
    with open(path, "w") as f:
        f.write(f"# epa-run/1\n# Ts={TS}\n# controller={controller}\n# source=blind-rig\n")
        closed = rows[0][1] is not None
        f.write("t_s,r_mm,y_mm,u_V,uc_V\n" if closed else "t_s,y_mm,u_V\n")
        for t, r, y, u, uc in rows:
            f.write(f"{t:.3f},{r:.3f},{y:.4f},{u:.5f},{uc:.5f}\n" if closed else f"{t:.3f},{y:.4f},{u:.5f}\n")
