"""Status codes shared by the wear results (evolutions, lives), and their meaning."""

STATUS_OK, STATUS_PIERCED, STATUS_SOLVER, STATUS_INCOMPLETE, STATUS_CONTACT_LOSS = 0, 1, 2, 3, 4

STATUS_TEXT = {
    STATUS_OK: "ok",
    STATUS_PIERCED: "the wear reached the bushing wall",
    STATUS_SOLVER: "the cycle model failed (integrator or equilibrium solve)",
    STATUS_INCOMPLETE: "the run ended (steps or cycles) before the wear limit was reached",
    STATUS_CONTACT_LOSS: ("the pin leaves the bushing wall during the cycle, where the "
                          "quasi-static model does not hold (use the dynamic model)"),
}
