"""Digital twin of a configurable slider-crank clearance test bench.

Start from :func:`twin.simulation.simulate` (a configuration in, a :class:`twin.run.Run`
out) or the ``twin`` command line (``twin --help``).
"""

__version__ = "0.4.0"
