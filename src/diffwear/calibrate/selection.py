"""Which effects the data show: identifiability, adoption and ambiguity.

**Identifiability.**  A fitted shape (a run-in's time scale, a film's depth)
is *determined* when the data shrink its prior: its posterior standard
deviation, in units of the prior's, is below `SHAPE_DETERMINED` (the data's
information on it about ten times the prior's).  When it is not, or when
it is but the strength then does not stand `STRENGTH_SIGMAS` from zero on
its own (strength and shape determined only together), only a combination
of the two is measured, and the candidate is stated in that identified
form: the extra worn volume the effect adds by an
inspection (`IdentifiedForm`; a run-in's by the first inspection: its
bedding-in), with the 1-sigma of that volume from the fit's covariance
(delta method through the model's exact derivatives).

**Adoption.**  A candidate qualifies when (a) its fit-set chi-square falls by
more than the chi-square critical value at p = 0.001 for the numbers it
determines (`LR_CRITICAL`; for a learned discrepancy, its effective number
of coefficients), (b) *what is reported* (the strength, or the identified
form) stands `STRENGTH_SIGMAS` standard deviations from zero on the allowed
side, at the uncertainty that is reported.  The penalised criterion
chi2_fit + prior rows + ln(n_fit) per determined number (BIC) ranks the
qualifying candidates.  Only the fit points enter: the held-out
measurements are read once, after the choice, for the before/after report.

**Ambiguity.**  The qualifying candidates whose criteria lie within
`AMBIGUITY` of the best (2 ln B < 6, below "strong" evidence on Kass and
Raftery's scale, J. Am. Stat. Assoc. 90 (1995) 773) form the window of
comparable explanations; within it the simplest ones (fewest causes, then
fewest determined numbers) stay, as in Occam's window (Madigan and
Raftery, J. Am. Stat. Assoc. 89 (1994) 1535).  One left is the answer; two
or more are an answer of their own: "A or B", with both fits and the
inspection that would separate them (`forecast`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import chi2
from .fit import FitResult, Fitter

# adoption's test level: a chi-square drop this improbable under "no effect"
P_ADOPT = 0.001
# chi-square critical values at p = 0.001 for 1 and 2 fitted numbers
LR_CRITICAL = {1: 10.83, 2: 13.82}
STRENGTH_SIGMAS = 3.0   # |reported value| / its std of an adopted effect
# posterior / prior std of a shape the data determine: the data hold at
# least ~10 times the prior's information on it (shapes fitted where the
# data see them come out at 0.01-0.07)
SHAPE_DETERMINED = 0.3
AMBIGUITY = 6.0         # criterion difference of two equally good candidates
# Effects stated, when their shape is not determined, by the extra volume
# worn before the first inspection (an early effect); the others by the
# extra volume at the last fitted inspection.
EARLY = ("run_in",)


@dataclass
class IdentifiedForm:
    """What the data determine of an effect whose shape they do not: the
    extra worn volume [m^3] it adds by ``cycles``, and its 1-sigma."""

    volume: float
    std: float
    cycles: float
    early: bool
    shape_determined: bool = False   # the shape is, but not apart from the strength
    shape_name: str = "shape"        # the effect's shape parameter, in words

    def sentence(self, effect: str) -> str:
        what = "bedding-in" if effect == "run_in" else effect.replace("_", " ")
        when = (f"before the first inspection ({self.cycles:g} cycles)" if self.early
                else f"by {self.cycles:g} cycles")
        unit = self.shape_name
        known = (f"its strength and {unit} are not determined apart from each other"
                 if self.shape_determined else
                 f"its {unit} cannot be measured from these data")
        return (f"{what}: {self.volume * 1e9:+.3g} +- {self.std * 1e9:.2g} mm^3 of extra wear "
                f"{when}; {known}")


@dataclass
class Assessment:
    """One candidate effect refitted on top of a reference model."""

    effect: str
    fit: FitResult
    reference: FitResult
    likelihood_ratio: float
    shape_determined: bool | None      # None: the effect has no shape
    value: float                       # what is reported: strength, or extra volume [m^3]
    std: float
    form: IdentifiedForm | None
    qualifies: bool
    reasons: list = field(default_factory=list)
    criterion: float = math.inf
    edf: float | None = None           # a discrepancy's effective number of coefficients

    @property
    def numbers(self) -> float:
        """Numbers the candidate adds that the data determine (1, or 2 with a
        shape determined apart from the strength; a discrepancy's effective
        number of coefficients)."""
        if self.edf is not None:
            return self.edf
        return 1 + (self.shape_determined is True and self.form is None)

    @property
    def z(self) -> float:
        return self.value / self.std if self.std > 0 else math.inf

    def entry(self) -> dict:
        """The effect as `summary.json` lists it."""
        f, e = self.fit, self.effect
        out = {"name": e, "strength": f.strengths[e], "strength_std": f.strengths_std[e],
               "shape": f.shapes.get(e), "shape_interval":
               list(f.shape_intervals[e]) if e in f.shape_intervals else None,
               "shape_determined": self.shape_determined, "z": self.z}
        if self.form is not None:
            out["identified_form"] = {
                "quantity": "extra worn volume", "value_mm3": self.form.volume * 1e9,
                "std_mm3": self.form.std * 1e9, "cycles": self.form.cycles,
                "sentence": self.form.sentence(e)}
        return out


def shape_determined(fit: FitResult, effect: str) -> bool | None:
    """Whether the data determine ``effect``'s shape in ``fit`` (module notes)."""
    lay = fit.notes["layout"]
    if effect not in lay.shaped:
        return None
    i = lay.n_base + len(lay.effects) + lay.shaped.index(effect)
    return math.sqrt(max(float(fit.notes["cov"][i, i]), 0.0)) < SHAPE_DETERMINED


def determined_numbers(fit: FitResult) -> float:
    """Numbers the data determine in ``fit`` beyond the base parameters: one
    per strength, one per shape determined apart from its strength, the
    effective number of a discrepancy's coefficients (the trace of its
    data-over-posterior information)."""
    n = float(len(fit.effects))
    n += sum(bool(shape_determined(fit, e)) and _apart(fit, e) for e in fit.effects)
    if fit.discrepancy is not None:
        n += fit.notes.get("discrepancy_edf", float(fit.n_discrepancy))
    return n


def _apart(fit: FitResult, effect: str) -> bool:
    """Whether ``effect``'s strength stands `STRENGTH_SIGMAS` from zero on its own."""
    std = fit.strengths_std[effect]
    return std > 0 and abs(fit.strengths[effect] / std) >= STRENGTH_SIGMAS


def criterion(fit: FitResult) -> float:
    """chi2_fit + the prior rows + ln(n_fit) per determined number (BIC, on
    the fit points only)."""
    return fit.chi2_fit + fit.prior_chi2 + determined_numbers(fit) * math.log(fit.n_fit)


def volumes(fitter: Fitter, fit: FitResult, zero: str | None = None):
    """(worn volume at the probe cycle counts, its derivative by the fit's
    unknowns), with ``zero``'s strength set to zero when given."""
    lay = fit.notes["layout"]
    z = np.array(fit.notes["z"], dtype=float)
    if zero is not None:
        z[lay.n_base + lay.effects.index(zero)] = 0.0
    lin = fitter.linearise(lay.pack(z), lay.tangents)
    jac = lin.volume_jac.copy()
    if zero is not None:
        jac[:, lay.n_base + lay.effects.index(zero)] = 0.0
    return lin.volume, jac


def identified_form(fitter: Fitter, fit: FitResult, effect: str,
                    inspections: list) -> IdentifiedForm | None:
    """The extra worn volume ``effect`` adds (module notes), or None without
    an inspection to state it at."""
    if not inspections:
        return None
    probes = list(fitter.problem.probe_cycles)
    early = effect in EARLY
    cycles = min(inspections) if early else max(inspections)
    k = int(np.argmin(np.abs(np.asarray(probes) - cycles)))
    v1, j1 = volumes(fitter, fit, None)
    v0, j0 = volumes(fitter, fit, effect)
    g = j1[k] - j0[k]
    var = float(g @ fit.notes["cov"] @ g)
    shape = fitter.library.effect(effect).shape
    return IdentifiedForm(float(v1[k] - v0[k]), math.sqrt(max(var, 0.0)), float(probes[k]),
                          early, shape_name=shape.name.replace("_", " ") if shape else "shape")


def assess(fitter: Fitter, effect: str, fit: FitResult, reference: FitResult,
           inspections: list) -> Assessment:
    """Whether ``effect`` (fitted in ``fit`` on top of ``reference``) qualifies
    (module notes)."""
    eff = fitter.library.effect(effect)
    lr = reference.chi2_fit - fit.chi2_fit
    determined = shape_determined(fit, effect)
    form = None
    value, std = fit.strengths[effect], fit.strengths_std[effect]
    apart = std > 0 and abs(value / std) >= STRENGTH_SIGMAS
    if determined is False or (determined is True and not apart):
        # a direction of (strength, shape) the data do not determine: the
        # effect is stated by the combination they do
        form = identified_form(fitter, fit, effect, inspections)
        if form is not None:
            form.shape_determined = bool(determined)
            value, std = form.volume, form.std
    numbers = 1 + (determined is True and form is None)
    reasons = []
    if not lr > LR_CRITICAL[numbers]:
        reasons.append(f"chi2 drop {lr:.3g} <= {LR_CRITICAL[numbers]}")
    z = value / std if std > 0 else math.inf
    if abs(z) < STRENGTH_SIGMAS:
        what = "extra volume" if form is not None else "strength"
        reasons.append(f"{what} {abs(z):.2g} sigma from zero (< {STRENGTH_SIGMAS:g})")
    if fit.strengths[effect] < eff.lower:
        reasons.append("strength outside its allowed range")
    return Assessment(effect, fit, reference, lr, determined, value, std, form,
                      not reasons, reasons, criterion(fit))


def assess_discrepancy(name: str, fit: FitResult, reference: FitResult) -> Assessment:
    """Whether the discrepancy ``name`` (fitted in ``fit`` on top of
    ``reference``) qualifies: its drop of the fit's penalised objective (the
    chi-square and the prior rows) beyond the p = `P_ADOPT` critical value
    for its effective number of coefficients (module notes)."""
    edf = float(fit.notes.get("discrepancy_edf", fit.n_discrepancy))
    lr = (reference.chi2_fit + reference.prior_chi2) - (fit.chi2_fit + fit.prior_chi2)
    critical = chi2.isf(P_ADOPT, max(edf, 1e-3))
    reasons = [] if lr > critical else [f"chi2 drop {lr:.3g} <= {critical:.3g} "
                                        f"({edf:.2g} effective coefficients)"]
    z = math.sqrt(max(lr, 0.0))  # the signed root of the likelihood ratio
    return Assessment(name, fit, reference, lr, None, z, 1.0, None, not reasons, reasons,
                      criterion(fit), edf)
