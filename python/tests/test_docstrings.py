"""Every public class, function, method and property of `tetrapage` carries a docstring of
prose, so that help(tetrapage.Index) reads like a manual page: pybind11's generated signature
lines do not count."""

import enum
import inspect
import re

import pytest

import tetrapage

# What pybind11 writes before a function's own text: `name(arg: type) -> type`, or, for several
# overloads, `name(*args, **kwargs)`, `Overloaded function.` and one `N. name(...)` per overload.
OVERLOADED = "Overloaded function."
# Prose: at least one word of three letters (not only a shape such as "(2, 3)").
WORD = re.compile(r"[A-Za-z]{3,}")


def signature_line(line, name):
    """Whether `line` is a signature pybind11 generated for the function `name`."""
    return re.match(r"(\d+\. )?" + re.escape(name) + r"\(.*\)( -> .*)?$", line.strip()) is not None


def prose_of_function(doc, name):
    """The text of each overload of a pybind11 function (one for a plain function), without the
    generated signature lines."""
    lines = (doc or "").strip().splitlines()
    if lines and signature_line(lines[0], name):
        lines = lines[1:]
    text = "\n".join(lines).strip()
    if not text.startswith(OVERLOADED):
        return [text]
    # One part per overload, each opened by its numbered signature.
    parts, current = [], None
    for line in text[len(OVERLOADED):].splitlines():
        if re.match(r"\d+\. ", line) and signature_line(line, name):
            current = []
            parts.append(current)
        elif current is not None:
            current.append(line)
    return ["\n".join(part).strip() for part in parts] or [""]


def prose_of_enum(doc):
    """An enum class's own text, without the `Members:` list pybind11 appends."""
    return re.split(r"^Members:\s*$", doc or "", maxsplit=1, flags=re.MULTILINE)[0].strip()


def has_prose(text):
    return WORD.search(text or "") is not None


def is_enum(cls):
    # pybind11's py::enum_ classes have __members__ (and __entries); Python's own are enum.Enum.
    return (isinstance(cls, type) and issubclass(cls, enum.Enum)) or hasattr(cls, "__entries")


def undocumented_members(cls):
    """`Class.member` for every public method and property (and __init__) of `cls` without
    prose."""
    missing = []
    for name, member in vars(cls).items():
        if name.startswith("_") and name != "__init__":
            continue
        what = f"{cls.__name__}.{name}"
        if isinstance(member, property):
            # pybind11 gives a property the text it was defined with, or "".
            if not has_prose(member.__doc__):
                missing.append(what)
            continue
        if isinstance(member, (staticmethod, classmethod)):
            member = member.__func__
        if name == "__init__" and not inspect.isroutine(member):
            continue
        if name == "__init__" and type(member).__name__ == "wrapper_descriptor":
            # No constructor bound (answers made by queries): pybind11's __init__ only raises
            # "No constructor defined!"; the class text says where its objects come from.
            continue
        if not callable(member):
            continue  # a constant: it has no docstring of its own
        if not all(has_prose(part) for part in prose_of_function(member.__doc__, name)):
            missing.append(what)
    return missing


def public_names():
    return sorted(name for name in dir(tetrapage) if not name.startswith("_"))


def test_every_public_name_has_prose():
    missing = []
    if not has_prose(tetrapage.__doc__):
        missing.append("tetrapage")
    classes = functions = 0
    for name in public_names():
        value = getattr(tetrapage, name)
        if inspect.isclass(value):
            classes += 1
            own = prose_of_enum(value.__doc__) if is_enum(value) else value.__doc__
            if not has_prose(own):
                missing.append(name)
            if not is_enum(value):
                missing += undocumented_members(value)
        elif inspect.isroutine(value):
            functions += 1
            if not all(has_prose(part) for part in prose_of_function(value.__doc__, name)):
                missing.append(name)
    # The walk saw the module's API (a wrong import would pass an empty walk).
    assert classes >= 10 and functions >= 5
    assert not missing, (f"{len(missing)} public names have no prose docstring (only a "
                         f"generated signature, or nothing): " + ", ".join(missing))


@pytest.mark.parametrize("doc, name, prose", [
    ("f(self: X, a: int) -> int\n\nThe thing.\n", "f", [True]),
    ("f(self: X, a: int) -> int\n", "f", [False]),
    (None, "f", [False]),
    ("", "f", [False]),
    ("(2, 3): the box.", "f", [True]),
    ("f(*args, **kwargs)\nOverloaded function.\n\n1. f(self: X) -> None\n\nOne.\n\n"
     "2. f(self: X, a: int) -> None\n\nTwo with a.\n", "f", [True, True]),
    ("f(*args, **kwargs)\nOverloaded function.\n\n1. f(self: X) -> None\n\nOne.\n\n"
     "2. f(self: X, a: int) -> None\n", "f", [True, False]),
])
def test_signature_lines_are_not_prose(doc, name, prose):
    assert [has_prose(part) for part in prose_of_function(doc, name)] == prose


def test_enum_members_list_is_not_prose():
    assert not has_prose(prose_of_enum("Members:\n\n  none\n\n  hit\n\n  unresolved"))
    assert has_prose(prose_of_enum("How a motion ends.\n\nMembers:\n\n  none\n\n  hit"))
