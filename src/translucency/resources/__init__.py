"""What a command needs before it works: memory and disk (:mod:`.memory`, its sizes and the machine's
memory in :mod:`.machine`) and time (:mod:`.timing`).

A shared home: the CLI states both before any work, and the stages' own estimates (the planar
acquisition's probe of its walk) feed them.
"""

from .machine import Need, memory_limit, parse_size
from .memory import check_resources
from .timing import TIME_TERMS, TimeEstimate, estimate_time, record_time

__all__ = [
    "TIME_TERMS",
    "Need",
    "TimeEstimate",
    "check_resources",
    "estimate_time",
    "memory_limit",
    "parse_size",
    "record_time",
]
