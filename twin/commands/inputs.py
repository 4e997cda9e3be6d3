"""Input arguments that may name a file shipped with the package (:mod:`twin.samples`), so the
README's commands work outside the repository: every command that reads a recording or a dataset
spec resolves its argument here.

* a recording: ``sample:NAME`` is the sample recording NAME (``sample:test6``); anything else is a path;
* a dataset spec: an existing file, or a text with a folder or the ``.toml`` suffix, is a path;
  otherwise a shipped spec's name (``tiny``; also when a folder of that name exists, such as the
  dataset ``--out tiny`` generated from it).
"""

from __future__ import annotations

import os
from pathlib import Path

from twin.errors import NameNotFoundError

#: the prefix that names a sample recording on the command line
SAMPLE_PREFIX = "sample:"
#: the help of a recording argument and of a dataset spec argument
RECORDING_HELP = ("bench recording (.mcap, recordings/FORMAT.md), or sample:NAME for a sample recording that ships "
                  "with twin (sample:test6)")
SPEC_HELP = "dataset spec: a .toml file, or the name of one that ships with twin (tiny)"


def is_sample(text: str) -> bool:
    """Whether a recording argument names a sample recording (``sample:NAME``)."""
    return text.startswith(SAMPLE_PREFIX)


def recording(text: str) -> Path:
    """The file of a recording argument: ``sample:NAME`` (:func:`twin.samples.path`) or a path.

    A path that does not exist but is a sample's name gets a one-line error saying how to name it."""
    from twin import samples

    if is_sample(text):
        try:
            return samples.path(text[len(SAMPLE_PREFIX):])
        except NameNotFoundError as err:
            raise NameNotFoundError(f"{text}: {err}") from None
    p = Path(text)
    if not p.exists() and text in samples.names():
        raise NameNotFoundError(f"{text}: no such file; the sample recording of that name is {SAMPLE_PREFIX}{text}")
    return p


def spec(text: str) -> Path:
    """The file of a dataset spec argument: a path (an existing file, or a text with a folder or the
    ``.toml`` suffix) or the name of a shipped spec (:func:`twin.samples.spec_path`)."""
    p = Path(text)
    # a folder of that name (the dataset generated from the spec: --out tiny) is not a spec: the name is looked up
    if not text or p.is_file() or "/" in text or os.sep in text or p.suffix.lower() == ".toml":
        return p
    from twin import samples

    try:
        return samples.spec_path(text)
    except NameNotFoundError:
        # the closest names, not all of them (over a hundred ship): the full list is `twin dataset list`
        names = samples.spec_names()
        close = closest_names(text, names)
        hint = f"closest: {', '.join(map(repr, close))}; " if close else ""
        raise NameNotFoundError(f"{text}: no such file, and no dataset spec named {text!r} ships with twin ({hint}"
                                f"'twin dataset list' lists all {len(names)})") from None


def closest_names(given: str, names: list[str], n: int = 5) -> list[str]:
    """Up to ``n`` entries of ``names`` closest to ``given`` (difflib's ratio at least 0.5, without case),
    closest first."""
    import difflib

    by_lower = {x.lower(): x for x in reversed(names)}
    return [by_lower[m] for m in difflib.get_close_matches(given.lower(), list(by_lower), n=n, cutoff=0.5)]
