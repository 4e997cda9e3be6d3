"""The base MJCF model of the bench (``bench.xml``), installed as the package ``twin.mjcf``
(setup.py maps this folder into the package, so the model ships in wheels and editable
installs alike; ``twin.names.BASE_XML`` locates it with :mod:`importlib.resources`)."""
