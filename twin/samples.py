"""The sample bench recordings and the dataset specs that ship with the package, by name.

The README's examples use them, so they work after ``pip install`` outside the repository:

>>> import twin.samples
>>> twin.samples.path("test6").name          # a sample recording (synthetic: see recordings/FORMAT.md)
'test6_synthetic.mcap'
>>> "test6_repeat1" in twin.samples.names()
True
>>> twin.samples.spec_path("tiny").name      # a dataset spec (twin dataset plan tiny)
'tiny.toml'

* :func:`names`, :func:`path`: the sample recordings, named by their file without ``_synthetic.mcap``
  (``test6`` is ``test6_synthetic.mcap``). The command line reads them as ``sample:NAME`` wherever it
  reads a recording (``twin replay sample:test6``).
* :func:`spec_names`, :func:`spec_path`: the dataset specs, named by their file without ``.toml``.
  The command line looks a spec argument up by name when it is not a file and has neither a folder
  nor the ``.toml`` suffix (``twin dataset plan tiny``).

There is one copy of each file: the repository's ``recordings/`` and ``analysis/datasets/`` folders,
which setup.py installs as the packages ``twin.sample_recordings`` and ``twin.dataset_specs`` (found
here with :mod:`importlib.resources`, in wheels and editable installs alike). An unknown name raises
:class:`~twin.errors.NameNotFoundError` (one line, the closest name and the list).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from twin.errors import NameNotFoundError, did_you_mean

#: the packages holding the files (setup.py maps the repository's folders to them)
RECORDINGS_PACKAGE = "twin.sample_recordings"
SPECS_PACKAGE = "twin.dataset_specs"
#: a sample recording's file is NAME + this suffix
RECORDING_SUFFIX = "_synthetic.mcap"
SPEC_SUFFIX = ".toml"


def _folder(package: str) -> Path:
    try:
        return Path(str(resources.files(package)))
    except ModuleNotFoundError:
        raise NameNotFoundError(f"this installation of twin holds no {package} package (the sample files); "
                                "reinstall twin") from None


def _names(package: str, suffix: str) -> list[str]:
    return sorted(p.name[:-len(suffix)] for p in _folder(package).iterdir()
                  if p.name.endswith(suffix) and p.is_file())


def _lookup(package: str, suffix: str, name: object, what: str) -> Path:
    names = _names(package, suffix)
    if not isinstance(name, str) or name not in names:
        raise NameNotFoundError(f"no {what} named {name!r}{did_you_mean(name, names)}; the {what}s: "
                                f"{', '.join(names)}")
    return _folder(package) / f"{name}{suffix}"


def names() -> list[str]:
    """The names of the sample recordings, sorted (``test6`` for ``test6_synthetic.mcap``)."""
    return _names(RECORDINGS_PACKAGE, RECORDING_SUFFIX)


def path(name: str) -> Path:
    """The file of the sample recording ``name`` (:func:`names`); an unknown name raises
    :class:`~twin.errors.NameNotFoundError` with the closest name and the list."""
    return _lookup(RECORDINGS_PACKAGE, RECORDING_SUFFIX, name, "sample recording")


def spec_names() -> list[str]:
    """The names of the shipped dataset specs, sorted (``tiny`` for ``tiny.toml``)."""
    return _names(SPECS_PACKAGE, SPEC_SUFFIX)


def spec_path(name: str) -> Path:
    """The file of the shipped dataset spec ``name`` (:func:`spec_names`); an unknown name raises
    :class:`~twin.errors.NameNotFoundError` with the closest name and the list."""
    return _lookup(SPECS_PACKAGE, SPEC_SUFFIX, name, "dataset spec")
