"""``translucency materials``: Jensen et al. 2001's measured coefficients and the dipole's R_d."""

from __future__ import annotations

import typer
from rich.table import Table

from .._validate import check_option
from ..model import MATERIALS, dipole_total_reflectance
from ._common import finish, json_option, user_errors


@user_errors
def materials(
    eta: float = typer.Option(1.3, help="Relative index of refraction for the dipole's total reflectance."),
    as_json: bool = json_option(),
):
    """Print Jensen et al. 2001's measured coefficients (mm^-1) and the dipole's R_d."""
    check_option("--eta", eta, lo=0, open_lo=True)

    table = Table(title=f"Jensen et al. 2001 measured materials (eta = {eta})")
    for col in ("name", "sigma_s' R G B [1/mm]", "sigma_a R G B [1/mm]", "R_d dipole", "R_d published"):
        table.add_column(col)
    fmt = lambda a: " ".join(f"{v:.4g}" for v in a)  # noqa: E731
    rows = {}
    for name, m in MATERIALS.items():
        rd = dipole_total_reflectance(m.sigma_a, m.sigma_s_prime, eta)
        table.add_row(name, fmt(m.sigma_s_prime), fmt(m.sigma_a), fmt(rd.round(3)), fmt(m.R_d_published))
        rows[name] = {
            "sigma_s_prime": m.sigma_s_prime,
            "sigma_a": m.sigma_a,
            "R_d_dipole": rd,
            "R_d_published": m.R_d_published,
        }
    finish(as_json, False, {"command": "materials", "eta": eta, "materials": rows}, [table])
