"""The sample bench recordings (``*_synthetic.mcap``, synthetic: made by ``make_samples.py``),
installed as the package ``twin.sample_recordings`` (setup.py maps this folder into the package, so
they ship in wheels and editable installs alike). Look them up by name with :mod:`twin.samples`
(``twin.samples.path("test6")``) or on the command line as ``sample:test6``."""
