"""tiremodal: roving-hammer tests of tyres turned into validated physical models.

Array and unit conventions are written down once, in ``docs/conventions.md``.
"""

__version__ = "0.1.0"
