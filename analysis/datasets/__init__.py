"""The dataset specs of the project (``*.toml``: the examples and those behind the shipped model and
the studies), installed as the package ``twin.dataset_specs`` (setup.py maps this folder into the
package, so they ship in wheels and editable installs alike). Look them up by name with
:mod:`twin.samples` (``twin.samples.spec_path("tiny")``) or on the command line
(``twin dataset plan tiny``)."""
