"""The names of the samples :func:`translucency.acquire.make_sample` generates.

Plain data, cheap to import: the CLI's ``--help`` lists them without loading the generators.
"""

#: the sample generators, in the order ``--help`` and the errors list them
GENERATORS = ("homogeneous:<name>", "marble", "apple-slice", "skin", "fibers", "banded", "layered")
