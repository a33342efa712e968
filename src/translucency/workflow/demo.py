"""The main job as the library runs it: :func:`translucency.pipeline.run_demo` (``translucency demo``,
``make demo``), the paper's Figure 1 on the embedded default data and Figure 2 on the alabaster pig."""

from ..pipeline.demo import DEMO_STEPS, run_demo

__all__ = ["DEMO_STEPS", "run_demo"]
