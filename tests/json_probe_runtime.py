"""The probe-check filter written from the JSON table's ``recalibration`` object alone (its numbers and steps).

Used by :func:`json_runtime.run_table` when it is given probes; like that
runtime it imports nothing of groupfit and computes on Python floats (IEEE
double) in the order the steps give.
"""

from __future__ import annotations


class ProbeFilter:
    def __init__(self, spec: dict, clamp: tuple[float, float]):
        self.spec = spec
        self.clamp_low, self.clamp_high = clamp
        self.x = [0.0, 0.0, 0.0]
        self.P = [[spec["p0"][i] if i == j else 0.0 for j in range(3)] for i in range(3)]
        self.applied = self.model = self.command = 0.0
        self.usable = False
        self.rejected = 0
        self.significant = False
        self.gap2 = 0.0

    def switched(self, gap: float) -> None:
        self.gap2 = self.gap2 + gap * gap

    def clamp(self) -> None:
        for i, bound in enumerate(self.spec["x_max"]):
            self.x[i] = max(min(self.x[i], bound), -bound)

    def propagate(self) -> None:
        x, P, phi = self.x, self.P, self.spec["phi"]
        x[0] = x[0] + x[1]
        x[1] = phi * x[1]
        A = [[P[0][j] + P[1][j] for j in range(3)], [phi * P[1][j] for j in range(3)], [P[2][j] for j in range(3)]]
        for i in range(3):
            P[i] = [A[i][0] + A[i][1], A[i][1] * phi, A[i][2]]
            P[i][i] = P[i][i] + self.spec["q"][i]
        self.clamp()

    def correct(self, model: float, held: bool, command: float) -> float:
        self.model, self.usable, self.command = model, not held, command
        rate = self.spec["rate_um"]
        target = self.x[0] + self.x[2] * model
        if self.spec["significance2"] > 0 and not self.significant:
            target = 0.0
        delta = max(min(target - self.applied, rate), -rate)
        self.applied = self.applied + delta
        return self.applied

    def projections(self):
        m, P = self.model, self.P
        ph = [P[i][0] + P[i][2] * m for i in range(3)]
        hp = [P[0][i] + P[2][i] * m for i in range(3)]
        return ph, hp, hp[0] + hp[2] * m + self.spec["r"]

    def probe(self, z: float) -> int:
        result = self.check(z)
        if result == self.spec["codes"]["applied"]:
            w = abs(z)
            w = w + w
            if w > self.clamp_high:
                self.clamp_high = min(w, self.spec["output_max_um"])
            if -w < self.clamp_low:
                self.clamp_low = max(-w, self.spec["output_min_um"])
            w = -max(min(-self.command, self.clamp_high), self.clamp_low)
            if w != self.model:
                self.x[0] = self.x[0] + (1.0 + self.x[2]) * (self.model - w)
                self.clamp()
                self.model = w
                self.significant = True
        return result

    def check(self, z: float) -> int:
        spec, codes, m, P = self.spec, self.spec["codes"], self.model, self.P
        if not self.usable or not (-spec["probe_limit_um"] <= z <= spec["probe_limit_um"]):
            return codes["ignored"]
        nu = (z - m) - (self.x[0] + self.x[2] * m)
        ph, hp, s = self.projections()
        if not s > 0:
            return codes["ignored"]
        gate = s + self.gap2
        if gate < spec["p0"][0]:
            gate = spec["p0"][0]
        self.gap2 = 0.0
        if nu * nu > spec["gate2"] * gate:
            if self.rejected < spec["confirm_after"]:
                self.rejected += 1
                return codes["rejected"]
            self.rejected = 0
            self.x[0] = self.x[0] + nu
            self.P = [[spec["p0"][i] if i == j else 0.0 for j in range(3)] for i in range(3)]
            self.clamp()
            self.significant = True
            return codes["applied"]
        self.rejected = 0
        k = [ph[i] / s for i in range(3)]
        for i in range(3):
            self.x[i] = self.x[i] + k[i] * nu
            P[i] = [P[i][j] - k[i] * hp[j] for j in range(3)]
        self.clamp()
        t = self.x[0] + self.x[2] * m
        _, hp, _ = self.projections()
        self.significant = t * t > spec["significance2"] * (hp[0] + hp[2] * m)
        return codes["applied"]
