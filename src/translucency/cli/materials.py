"""``translucency materials``: Jensen et al. 2001's measured coefficients and the dipole's R_d
(:func:`translucency.workflow.inspecting.describe_materials`)."""

from __future__ import annotations

import typer
from rich.table import Table

from ._common import finish, json_option, user_errors


@user_errors
def materials(
    eta: float = typer.Option(1.3, help="Relative index of refraction for the dipole's total reflectance."),
    as_json: bool = json_option(),
):
    """Print Jensen et al. 2001's measured coefficients (mm^-1) and the dipole's R_d."""
    from ..workflow.inspecting import describe_materials  # the model's closed forms, NumPy only

    record = describe_materials(eta)
    table = Table(title=f"Jensen et al. 2001 measured materials (eta = {eta})")
    for col in ("name", "sigma_s' R G B [1/mm]", "sigma_a R G B [1/mm]", "R_d dipole", "R_d published"):
        table.add_column(col)
    fmt = lambda a: " ".join(f"{v:.4g}" for v in a)  # noqa: E731
    for name, m in record["materials"].items():
        table.add_row(
            name,
            fmt(m["sigma_s_prime"]),
            fmt(m["sigma_a"]),
            fmt(m["R_d_dipole"].round(3)),
            fmt(m["R_d_published"]),
        )
    finish(as_json, False, record, [table])
