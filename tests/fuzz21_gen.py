"""Seeded generator of varied, legal Delta NC5 programs (mill and lathe type A) for tests/test_fuzz21_random.py.

Each fragment is a small job a user would write (lines with zero-length and µm blocks, arcs in G17/G18/G19 with
I/J/K or R, full circles, helices, major arcs, G91 arcs, G41/G42 contours and pockets, G43/G49, G54–G59/G52/G92,
G68, G51, G16, the hole cycles, G04, M98 H/M99, WHILE/IF/GOTO, S/M codes; lathe G71/G72/G70/G76/G90/G92/G94,
nose radius compensation, G83/G85). Every number has a decimal point (decision A4: an integer is µm), and each
fragment leaves the machine as it found it (G90 G17, no compensation or transform, the tool at a safe Z/X).
"""
from __future__ import annotations

import math
import random


def f(v: float) -> str:
    """A number always written with a decimal point (A4: an integer would be µm)."""
    s = f"{v:.3f}".rstrip("0")
    if s.endswith("."):
        return s
    return s if "." in s else s + "."


class Mill:
    def __init__(self, seed: int, quick: bool = False):
        self.r = random.Random(seed)
        self.feeds = [1500., 3000., 6000.] if quick else [50., 120., 300., 800., 1500., 3000., 6000.]
        self.out: list[str] = []
        self.subs: list[str] = []
        self.label = 100
        self.x = self.y = 0.0
        self.z = 30.0

    def emit(self, *lines: str) -> None:
        self.out.extend(lines)

    def pt(self, span: float = 40.0) -> tuple[float, float]:
        r = self.r
        return round(r.uniform(-span, span), 3), round(r.uniform(-span, span), 3)

    def feed(self) -> str:
        return f"F{f(self.r.choice(self.feeds))}"

    def safe(self) -> None:
        self.emit(f"G90 G00 Z{f(30.)}")
        self.z = 30.0

    # ---- fragments; each leaves G90 G17, no comp/transform, tool at Z30 work
    def lines(self) -> None:
        r = self.r
        self.emit(f"G01 Z{f(r.uniform(-5, 2))} {self.feed()}")
        for _ in range(r.randint(2, 8)):
            k = r.random()
            if k < 0.15:
                self.emit(f"X{f(self.x)} Y{f(self.y)}")  # zero-length block
            elif k < 0.3:
                self.x += 0.001 * r.choice([1, -1, 3])
                self.emit(f"X{f(self.x)}")  # a 1-3 µm block
            elif k < 0.45:
                dx, dy = round(r.uniform(-10, 10), 3), round(r.uniform(-10, 10), 3)
                self.x += dx
                self.y += dy
                self.emit(f"G91 G01 X{f(dx)} Y{f(dy)}", "G90")
            else:
                self.x, self.y = self.pt()
                fw = f" {self.feed()}" if r.random() < 0.4 else ""
                self.emit(f"X{f(self.x)} Y{f(self.y)}{fw}")
        self.safe()

    def arcs(self) -> None:
        r = self.r
        plane = r.choice(["G17", "G17", "G18", "G19"])
        self.emit(f"G00 X{f(self.x)} Y{f(self.y)}", f"G01 Z{f(0.)} {self.feed()}")
        self.z = 0.0
        a, b = ("X", "Y") if plane == "G17" else (("Z", "X") if plane == "G18" else ("Y", "Z"))
        ia, ib = {"X": "I", "Y": "J", "Z": "K"}[a], {"X": "I", "Y": "J", "Z": "K"}[b]
        self.emit(plane)
        pos = {"X": self.x, "Y": self.y, "Z": self.z}
        for _ in range(r.randint(1, 5)):
            g = r.choice(["G02", "G03"])
            kind = r.random()
            rad = r.choice([0.05, 0.5, 3., 10., 25.]) if kind > 0.1 else 0.002
            ang0 = r.uniform(0, 2 * math.pi)
            ca, cb = pos[a] - rad * math.cos(ang0), pos[b] - rad * math.sin(ang0)
            if r.random() < 0.3:  # full circle
                ea, eb = pos[a], pos[b]
                extra = ""
                if plane == "G17" and r.random() < 0.5:  # helix
                    dz = round(r.uniform(-3, 0), 3)
                    pos["Z"] += dz
                    extra = f" Z{f(pos['Z'])}"
                self.emit(f"{g} {a}{f(ea)} {b}{f(eb)}{extra} {ia}{f(round(ca - pos[a], 3))} {ib}{f(round(cb - pos[b], 3))}")
                continue
            sweep = r.uniform(0.05, 3.0)
            ang1 = ang0 + (sweep if g == "G03" else -sweep)
            ea, eb = round(ca + rad * math.cos(ang1), 3), round(cb + rad * math.sin(ang1), 3)
            extra = ""
            if plane == "G17" and r.random() < 0.3:
                pos["Z"] = round(pos["Z"] + r.uniform(-2, 0), 3)
                extra = f" Z{f(pos['Z'])}"
            if r.random() < 0.5 and sweep < math.pi * 0.98 and rad >= 0.05:
                rr = math.dist((ea, eb), (pos[a], pos[b])) / 2
                self.emit(f"{g} {a}{f(ea)} {b}{f(eb)}{extra} R{f(max(rad, rr + 0.001))}")
            else:
                self.emit(f"{g} {a}{f(ea)} {b}{f(eb)}{extra} {ia}{f(round(ca - pos[a], 3))} {ib}{f(round(cb - pos[b], 3))}")
            pos[a], pos[b] = ea, eb
        self.x, self.y, self.z = pos["X"], pos["Y"], pos["Z"]
        self.emit("G17")
        self.safe()

    def comp(self) -> None:
        r = self.r
        d = r.randint(1, 20)
        rad = round(r.uniform(0.5, 6), 3)
        self.emit(f"G10 L12 P{d} R{f(rad)}")
        cx, cy = self.pt(20)
        w, h = round(r.uniform(3 * rad + 2, 40), 3), round(r.uniform(3 * rad + 2, 30), 3)
        side = r.choice(["G41", "G42"])
        self.emit(f"G00 X{f(cx - w - 15)} Y{f(cy - h - 15)}", f"G01 Z{f(-2.)} {self.feed()}")
        self.emit(f"{side} D{d} G01 X{f(cx - w)} Y{f(cy - h)}")
        shape = r.random()
        if shape < 0.5:
            self.emit(f"X{f(cx + w)}", f"Y{f(cy + h)}", f"X{f(cx - w)}", f"Y{f(cy - h)}")
        else:
            rr = round(r.uniform(rad + 1, min(w, h)), 3)
            self.emit(f"X{f(cx + w - rr)}", f"G03 X{f(cx + w)} Y{f(cy - h + rr)} R{f(rr)}",
                      f"G01 Y{f(cy + h)}", f"X{f(cx - w)}", f"Y{f(cy - h)}")
        self.x, self.y = cx - w - 15, cy - h - 15
        self.emit(f"G40 G01 X{f(self.x)} Y{f(self.y)}")
        self.safe()

    def length(self) -> None:
        r = self.r
        h = r.randint(1, 30)
        self.emit(f"G10 L10 P{h} R{f(r.uniform(-40, 40))}", f"G43 H{h} Z{f(20.)}")
        self.x, self.y = self.pt()
        self.emit(f"G01 X{f(self.x)} Y{f(self.y)} Z{f(5.)} {self.feed()}", "G49")
        self.safe()

    def offsets(self) -> None:
        r = self.r
        k = r.random()
        if k < 0.4:
            p = r.randint(1, 6)
            self.emit(f"G10 L2 P{p} X{f(r.uniform(-30, 30))} Y{f(r.uniform(-30, 30))} Z{f(r.uniform(-20, 0))}",
                      f"G{53 + p}")
            self.emit(f"G00 X{f(self.x)} Y{f(self.y)}")
        elif k < 0.7:
            self.emit(f"G52 X{f(r.uniform(-20, 20))} Y{f(r.uniform(-20, 20))}")
            self.lines()
            self.emit(f"G52 X{f(0.)} Y{f(0.)} Z{f(0.)}")
        else:
            cx, cy = self.pt(20)
            self.emit(f"G00 X{f(self.x)} Y{f(self.y)}", f"G92 X{f(cx)} Y{f(cy)}")
            px, py = cx, cy
            for _ in range(r.randint(1, 4)):
                px, py = round(cx + r.uniform(-20, 20), 3), round(cy + r.uniform(-20, 20), 3)
                self.emit(f"G01 X{f(px)} Y{f(py)} {self.feed()}")
            self.emit(f"G00 X{f(cx)} Y{f(cy)}", f"G92 X{f(self.x)} Y{f(self.y)}")

    def _transformed(self, on, span: float, last: float, arc) -> None:
        """A few lines and an arc between a transform's `on(cx, cy)` block and its cancel."""
        cx, cy = self.pt(10)
        self.emit(on(cx, cy))
        for _ in range(self.r.randint(1, 4)):
            x, y = self.pt(span)
            self.emit(f"G01 X{f(x)} Y{f(y)} {self.feed()}")
        end = arc(*self.pt(last))
        if end:
            self.emit(end)

    def rotate(self) -> None:
        r = self.r
        self._transformed(lambda cx, cy: f"G68 X{f(cx)} Y{f(cy)} R{f(r.uniform(-180, 360))}", 25, 25,
                          lambda x, y: f"G02 X{f(x)} Y{f(y)} R{f(60.)}" if r.random() < 0.5 else None)
        self.emit("G69", f"G00 X{f(self.x)} Y{f(self.y)}")

    def scale(self) -> None:
        r = self.r
        self._transformed(lambda cx, cy: f"G51 X{f(cx)} Y{f(cy)} P{r.choice([500, 1000, 1500, 2000, 250])}", 20, 15,
                          lambda x, y: f"G03 X{f(x)} Y{f(y)} R{f(40.)}")
        self.emit("G50", f"G00 X{f(self.x)} Y{f(self.y)}")

    def cycle(self) -> None:
        r = self.r
        code = r.choice(["G73", "G81", "G82", "G83", "G84", "G74", "G85", "G86", "G89", "G76"])
        ret = r.choice(["G98", "G99"])
        z = round(r.uniform(-15, -1), 3)
        rr = round(r.uniform(1, 5), 3)
        words = f"Z{f(z)} R{f(rr)}"
        if code in ("G73", "G83"):
            words += f" Q{f(r.uniform(0.5, 4))}"
        if code in ("G82", "G89", "G76"):
            words += f" P{r.randint(0, 500)}"
        if code == "G76":
            words += f" Q{f(r.uniform(0.1, 0.5))}"
        if code in ("G74", "G84"):
            self.emit("M03 S500" if code == "G84" else "M04 S500")
            feed = "F500."
        else:
            feed = self.feed()
        x, y = self.pt()
        k = f" K{r.randint(0, 3)}" if r.random() < 0.3 else ""
        self.emit(f"{ret} {code} X{f(x)} Y{f(y)} {words}{k} {feed}")
        for _ in range(r.randint(0, 3)):
            if r.random() < 0.3:
                self.emit(f"G91 X{f(r.uniform(-5, 5))} Y{f(r.uniform(-5, 5))}", "G90")
            else:
                x, y = self.pt()
                self.emit(f"X{f(x)} Y{f(y)}")
        self.emit("G80")
        self.emit("M03 S3000")
        self.safe()
        self.emit(f"G00 X{f(self.x)} Y{f(self.y)}")

    def dwell(self) -> None:
        self.emit(self.r.choice([f"G04 X{f(self.r.uniform(0, 0.3))}", f"G04 P{self.r.randint(0, 300)}"]))

    def sub(self) -> None:
        r = self.r
        self.label += 10
        n = self.label
        x, y = self.pt(20)
        body = [f"N{n} G01 X{f(x)} Y{f(y)} {self.feed()}", f"G91 G01 X{f(r.uniform(-3, 3))}", "G90"]
        if r.random() < 0.4:
            body.append(f"#{500 + n % 50}=#{500 + n % 50}+1")
        body.append("M99")
        self.subs.extend(body)
        reps = f" L{r.randint(1, 3)}" if r.random() < 0.5 else ""
        self.emit(f"M98 H{n}{reps}", f"G90 G00 X{f(self.x)} Y{f(self.y)}")

    def macro(self) -> None:
        r = self.r
        v = r.randint(100, 199)
        n = r.randint(2, 6)
        step = round(r.uniform(1, 8), 3)
        self.emit(f"#{v}=0", f"#{v + 1}={f(step)}")
        self.emit(f"WHILE[#{v}LT{n}]DO1",
                  f"G01 X[#{v}*#{v + 1}-20.] Y[SIN[#{v}*30.]*10.] {self.feed()}",
                  f"#{v}=#{v}+1", "END1")
        self.label += 10
        lab = self.label
        self.emit(f"IF[#{v}GE{n}]GOTO{lab}", f"G01 X{f(99.)}", f"N{lab} #{v + 2}=ROUND[#{v}*1.5]",
                  f"IF[#{v + 2}==0]THEN", f"G01 Y{f(1.)}", "ELSE", f"G01 Y[-#{v + 2}]", "ENDIF")
        self.x, self.y = (n - 1) * step - 20.0, -float(round((n) * 1.5 + 1e-9))
        self.emit(f"G00 X{f(self.x)} Y{f(self.y)}")  # re-sync the generator's position
        self.safe()

    def spindle(self) -> None:
        r = self.r
        self.emit(r.choice(["M03", "M04"]) + f" S{r.randint(100, 8000)}", r.choice(["M08", "M09", "M05 M09", "S2000"]),
                  "M03 S3000")


    def arc_major(self) -> None:
        r = self.r
        rad = round(r.uniform(5, 20), 3)
        ang = r.uniform(0, 6.28)
        ex, ey = round(self.x + rad * 1.2 * math.cos(ang), 3), round(self.y + rad * 1.2 * math.sin(ang), 3)
        self.emit(f"G01 Z{f(-1.)} {self.feed()}", f"{r.choice(['G02', 'G03'])} X{f(ex)} Y{f(ey)} R{f(-rad)}")
        self.x, self.y = ex, ey
        self.safe()

    def comp_rot(self) -> None:
        r = self.r
        d = r.randint(1, 20)
        rad = round(r.uniform(0.5, 4), 3)
        self.emit(f"G10 L12 P{d} R{f(rad)}", f"G68 X{f(0.)} Y{f(0.)} R{f(r.uniform(0, 360))}")
        w = round(r.uniform(3 * rad + 2, 25), 3)
        self.emit(f"G00 X{f(-w - 10)} Y{f(-w - 10)}", f"G01 Z{f(-1.)} {self.feed()}",
                  f"{r.choice(['G41', 'G42'])} D{d} X{f(-w)} Y{f(-w)}")
        if r.random() < 0.5:
            self.emit(f"Y{f(w)}", f"X{f(w)}", f"Y{f(-w)}", f"X{f(-w)}")
        else:
            self.emit(f"X{f(0.)}", f"G03 X{f(0.)} Y{f(-w)} I{f(0.)} J{f(w)}", f"G01 X{f(w)}")
        self.emit(f"G40 G01 X{f(-w - 10)} Y{f(-w - 10)}", "G69")
        self.safe()
        self.emit(f"G00 X{f(self.x)} Y{f(self.y)}")

    def comp_pocket(self) -> None:
        r = self.r
        d = r.randint(1, 20)
        rad = round(r.uniform(0.5, 3), 3)
        big = round(r.uniform(rad + 2, 20), 3)
        cx, cy = self.pt(20)
        self.emit(f"G10 L12 P{d} R{f(rad)}", f"G00 X{f(cx)} Y{f(cy)}", f"G01 Z{f(-1.)} {self.feed()}",
                  f"G41 D{d} G01 X{f(cx + big)} Y{f(cy)}", f"G03 I{f(-big)} J{f(0.)}",
                  f"G40 G01 X{f(cx)} Y{f(cy)}")
        self.x, self.y = cx, cy
        self.safe()

    def inc_arcs(self) -> None:
        r = self.r
        self.emit(f"G01 Z{f(-1.)} {self.feed()}")
        for _ in range(r.randint(1, 4)):
            rad = round(r.uniform(0.5, 10), 3)
            a0 = r.uniform(0, 6.28)
            sw = r.uniform(0.1, 3)
            g = r.choice(["G02", "G03"])
            a1 = a0 + (sw if g == "G03" else -sw)
            i, j = round(-rad * math.cos(a0), 3), round(-rad * math.sin(a0), 3)
            cx, cy = self.x + i, self.y + j
            ex, ey = round(cx + rad * math.cos(a1), 3), round(cy + rad * math.sin(a1), 3)
            self.emit(f"G91 {g} X{f(round(ex - self.x, 3))} Y{f(round(ey - self.y, 3))} I{f(i)} J{f(j)}", "G90")
            self.x, self.y = self.x + round(ex - self.x, 3), self.y + round(ey - self.y, 3)
        self.x, self.y = round(self.x, 3), round(self.y, 3)
        self.emit(f"G00 X{f(self.x)} Y{f(self.y)}")
        self.safe()

    def polar(self) -> None:
        r = self.r
        self.emit("G16")
        for _ in range(r.randint(1, 4)):
            self.emit(f"G01 X{f(r.uniform(1, 40))} Y{f(r.uniform(-360, 360))} {self.feed()}")
        self.emit("G15", f"G00 X{f(self.x)} Y{f(self.y)}")

    def cycle_inc(self) -> None:
        r = self.r
        self.emit(f"G00 Z{f(10.)}")
        self.z = 10.0
        self.emit(f"G91 G99 G81 X{f(r.uniform(-5, 5))} Y{f(r.uniform(-5, 5))} Z{f(-r.uniform(1, 5))} "
                  f"R{f(-r.uniform(1, 8))} K{r.randint(1, 4)} {self.feed()}", "G80 G90")
        self.emit(f"G00 X{f(self.x)} Y{f(self.y)}")
        self.safe()

    def program(self, nfrag: int) -> str:
        r = self.r
        self.emit("G21 G17 G90 G40 G49 G80 G54", "M03 S3000", f"G00 X{f(0.)} Y{f(0.)} Z{f(30.)}")
        frags = [self.lines, self.arcs, self.comp, self.length, self.offsets, self.rotate, self.scale,
                 self.cycle, self.dwell, self.sub, self.macro, self.spindle, self.arc_major, self.comp_rot,
                 self.comp_pocket, self.inc_arcs, self.polar, self.cycle_inc]
        for _ in range(nfrag):
            r.choice(frags)()
        self.safe()
        self.emit("G54", "M05", "M30")
        return "\n".join(self.out + self.subs) + "\n"


class Lathe:
    """Type A lathe, diameter programming (X is a diameter), G18."""

    def __init__(self, seed: int):
        self.r = random.Random(seed)
        self.out: list[str] = []
        self.subs: list[str] = []
        self.label = 100
        self.lab_p = 1000

    def emit(self, *lines: str) -> None:
        self.out.extend(lines)

    def profile_blocks(self, d0: float, d1: float, z1: float) -> list[str]:
        """A monotone OD profile from diameter d0 at Z0 to d1 at z1 (X rising, Z falling)."""
        r = self.r
        n = r.randint(2, 5)
        xs = sorted(round(r.uniform(d0, d1), 3) for _ in range(n))
        zs = sorted((round(r.uniform(z1, -0.5), 3) for _ in range(n)), reverse=True)
        out = [f"G01 Z{f(0.)} F{f(r.choice([0.08, 0.15, 0.25]))}"]
        for x, z in zip(xs, zs):
            k = r.random()
            if k < 0.35:
                out += [f"X{f(x)}", f"Z{f(z)}"]
            elif k < 0.55:
                out += [f"X{f(x)} Z{f(z)}"]
            else:
                out += [f"Z{f(z)}", f"X{f(x)}"]
        out += [f"X{f(44.)}"]  # out of the stock, below the start point X45
        return out

    def g71(self) -> None:
        r = self.r
        self.lab_p += 100
        p, q = self.lab_p, self.lab_p + 50
        d1 = round(r.uniform(30, 40), 3)
        d0 = round(r.uniform(8, 20), 3)
        prof = self.profile_blocks(d0, d1, round(r.uniform(-40, -10), 3))
        start = f"N{p} G00 X{f(d0)}"
        body = [start] + prof[:-1] + [f"N{q} {prof[-1]}"]
        self.emit("G00 X45. Z5.", f"G71 U{f(r.uniform(0.5, 2.5))} R{f(r.uniform(0.2, 1))}",
                  f"G71 P{p} Q{q} U{f(r.uniform(0, 0.5))} W{f(r.uniform(0, 0.2))} F{f(r.choice([0.2, 0.3]))}")
        self.emit(*body)
        if r.random() < 0.7:
            comp = r.random() < 0.5
            if comp:
                self.emit("G42 G00 X45. Z2.")
            self.emit(f"G70 P{p} Q{q}")
            if comp:
                self.emit("G40 G00 X60. Z20.")
        self.emit("G00 X60. Z20.")

    def g72(self) -> None:
        r = self.r
        self.lab_p += 100
        p, q = self.lab_p, self.lab_p + 50
        z1 = round(r.uniform(-8, -3), 3)
        self.emit("G00 X45. Z2.", f"G72 W{f(r.uniform(0.5, 2))} R{f(r.uniform(0.2, 1))}",
                  f"G72 P{p} Q{q} U{f(r.uniform(0, 0.4))} W{f(r.uniform(0, 0.2))} F{f(0.2)}")
        self.emit(f"N{p} G00 Z{f(z1)}", f"G01 X{f(30.)} F{f(0.15)}", f"Z{f(z1 / 2)}",
                  f"X{f(r.uniform(12, 20))} Z{f(0.)}", f"N{q} X{f(10.)}")
        if r.random() < 0.5:
            self.emit(f"G70 P{p} Q{q}")
        self.emit("G00 X60. Z20.")

    def g76(self) -> None:
        r = self.r
        d = r.choice([(24., 2.), (20., 1.5), (30., 1.)])
        h = round(0.6134 * d[1], 3)
        self.emit("G97 S800 M03", f"G00 X{f(d[0] + 4)} Z{f(5.)}",
                  f"G76 P{r.choice(['01', '02'])}{r.choice(['00', '10'])}60 Q{r.randint(30, 100)} R{f(0.05)}",
                  f"G76 X{f(round(d[0] - 2 * h, 3))} Z{f(round(r.uniform(-30, -10), 3))} P{int(h * 1000)} "
                  f"Q{r.randint(200, 500)} F{f(d[1])}",
                  "G00 X60. Z20.", "G96 S180 M03")

    def single(self) -> None:
        r = self.r
        code = r.choice(["G90", "G94", "G92"])
        if code == "G90":
            self.emit("G00 X42. Z2.")
            for x in sorted((round(r.uniform(25, 40), 3) for _ in range(r.randint(1, 3))), reverse=True):
                self.emit(f"G90 X{f(x)} Z{f(r.uniform(-30, -5))} F{f(0.2)}")
        elif code == "G94":
            self.emit("G00 X42. Z2.")
            for z in sorted((round(r.uniform(-4, -0.5), 3) for _ in range(r.randint(1, 3))), reverse=True):
                self.emit(f"G94 X{f(r.uniform(5, 20))} Z{f(z)} F{f(0.2)}")
        else:
            self.emit("G97 S600 M03", "G00 X30. Z5.")
            for x in (23.2, 22.6, 22.2):
                self.emit(f"G92 X{f(x)} Z{f(-20.)} F{f(1.5)}")
            self.emit("G96 S180 M03")
        self.emit("G00 X60. Z20.")

    def contour(self) -> None:
        r = self.r
        comp = r.random() < 0.5
        self.emit("G00 X45. Z5.")
        if comp:
            self.emit(f"G42 G00 X{f(20.)} Z{f(2.)}")
        else:
            self.emit(f"G00 X{f(20.)} Z{f(2.)}")
        self.emit(f"G01 Z{f(0.)} F{f(0.15)}")
        x, z = 20.0, 0.0
        for _ in range(r.randint(2, 6)):
            k = r.random()
            if k < 0.3:
                z = round(z - r.uniform(2, 8), 3)
                self.emit(f"Z{f(z)}")
            elif k < 0.5:
                nx = round(x + r.uniform(4, 8), 3)
                self.emit(f"X{f(nx)} Z{f(round(z - r.uniform(2, 3), 3))}")
                z = float(self.out[-1].split("Z")[1])
                x = nx
            elif k < 0.7:
                rad = round(r.uniform(1, 4), 3)
                self.emit(f"G02 X{f(x + 2 * rad)} Z{f(round(z - rad, 3))} R{f(rad)}")
                x, z = x + 2 * rad, round(z - rad, 3)
                self.emit("G01")
            elif k < 0.8:
                self.emit(f"W{f(-3.)}")
                z = round(z - 3, 3)
            elif k < 0.9:
                self.emit(f"Z{f(z)}")  # zero length
            else:
                self.emit(f"U{f(5.)}")
                x += 5
        self.emit(f"X{f(x + 6)}")
        if comp:
            self.emit("G40 G00 X60. Z20.")
        else:
            self.emit("G00 X60. Z20.")

    def drill(self) -> None:
        r = self.r
        code = r.choice(["G83", "G85", "G83"])
        q = f" Q{r.randint(1000, 4000)}" if code == "G83" else ""
        self.emit("G97 S800 M03", "G00 X0. Z5.", f"{code} X0. Z{f(-r.uniform(5, 20))} R{f(-2.)}{q} F{f(0.1)}",
                  "G80", "G00 X60. Z20.", "G96 S180 M03")

    def dwell(self) -> None:
        self.emit(self.r.choice([f"G04 X{f(self.r.uniform(0, 0.3))}", f"G04 U{f(0.1)}", f"G04 P{self.r.randint(0, 300)}"]))

    def macro(self) -> None:
        r = self.r
        v = r.randint(100, 150)
        self.emit("G00 X45. Z2.", f"#{v}=0", f"WHILE[#{v}LT{r.randint(1, 4)}]DO1",
                  f"G01 X[40.-#{v}*2.] F{f(0.2)}", f"Z[-5.-#{v}]", f"G00 X45.", "Z2.", f"#{v}=#{v}+1", "END1",
                  "G00 X60. Z20.")

    def sub(self) -> None:
        self.label += 10
        n = self.label
        self.subs += [f"N{n} G00 X45. Z2.", f"G01 X{f(self.r.uniform(30, 40))} F{f(0.2)}", "G00 X60. Z20.", "M99"]
        self.emit(f"M98 H{n}")

    def tool(self) -> None:
        t = self.r.choice([1, 3])
        self.emit(f"T{t:02d}{t:02d}")

    def program(self, nfrag: int) -> str:
        r = self.r
        self.emit("G10 L10 P1 R0.8 Q3", "G10 L10 P3 R0. Q0", "G21 G99", "G50 S2500", "T0101", "G96 S180 M03",
                  "G00 X60. Z20.")
        frags = [self.g71, self.g72, self.g76, self.single, self.contour, self.drill, self.dwell, self.macro,
                 self.sub, self.tool]
        for _ in range(nfrag):
            r.choice(frags)()
        self.emit("G00 X60. Z20.", "M05", "M30")
        return "\n".join(self.out + self.subs) + "\n"


def program(kind: str, seed: int, fragments: int, quick: bool = False) -> str:
    """The program of `seed`: "mill" (benches/mill-3axis.toml) or "lathe" (benches/lathe-2axis.toml); `quick`:
    the mill's feeds from 1500 mm/min up (seconds of simulated time, not minutes)."""
    return (Mill(seed, quick) if kind == "mill" else Lathe(seed)).program(fragments)


if __name__ == "__main__":  # python tests/fuzz21_gen.py mill 7 6 > p.nc
    import sys
    print(program(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]) if len(sys.argv) > 3 else 6), end="")
