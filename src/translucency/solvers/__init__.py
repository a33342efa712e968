"""Batched least-squares solvers shared by the stages that fit profiles.

:func:`fit_exponentials_batched` (:mod:`.varpro`) fits sums of exponentials to many weighted
profiles at once by variable projection — the fitter's hot path (:mod:`translucency.fit`) and the
beam-width correction of a rig's windows (:mod:`translucency.rig.planar.beam`);
:func:`fit_params_batched` (:mod:`.lm`) fits two-parameter baseline profiles (dipole, Burley, …)
by batched Levenberg–Marquardt.  A shared home: fit and rig both use them, neither owns them.
"""

from .lm import fit_params_batched
from .varpro import fit_exponentials_batched, nnls_small, rate_bounds

__all__ = ["fit_exponentials_batched", "fit_params_batched", "nnls_small", "rate_bounds"]
