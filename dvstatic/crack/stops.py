"""When the event loop stops after an event: the body separated, became a mechanism or
singular, or the load fell below a share of its peak."""

from __future__ import annotations

import numpy as np

__all__ = ["stop_after", "MECHANISM"]

#: secant stiffness (relative to the initial one) below which the body is a mechanism
MECHANISM = 1e-6


def stop_after(pieces, d, removed, ends, model, ev, peak, res, ratio, k, stiffness):
    """(reason, message) if the analysis must stop after this event, else None."""
    if removed:
        msg = pieces.hanging(d, ends, model.operator.spring) or pieces.check(d)
        if msg is not None:
            return "separated", msg
    if not stiffness > MECHANISM:
        return "separated", (
            f"after event {k} the secant stiffness is {stiffness:.1e} of the initial one: "
            "the body hangs on broken or nearly broken bonds (a mechanism)"
        )
    if ratio and peak > 0 and ev.load < ratio * peak:
        return "load_drop", f"the load fell below {ratio:g} of the peak {peak:.6g}"
    if not np.isfinite(res) or res > 1e-6:
        return "separated", (
            f"the damaged stiffness became singular at event {k} (relative residual "
            f"{res:.2e}): the body has come apart"
        )
    return None
