"""Reading an effect out of a calibration's answer (``summary.json``)."""


def answer_entry(summary: dict, effect: str) -> dict:
    """``effect``'s entry in a calibration's answer: the effect named, or one
    side of an "A or B" answer that names the inspection separating them."""
    for e in summary["effects_identified"]:
        if e.get("ambiguous"):
            assert summary["next_measurement"]["expected_separation_sigma"] > 0
            for a in e["alternatives"]:
                for x in a["effects"]:
                    if x["name"] == effect:
                        return x
        elif e["name"] == effect:
            assert summary["effect_identified"] == effect
            return e
    raise AssertionError(f"{effect} is not in the answer: {summary['effects_identified']}")
