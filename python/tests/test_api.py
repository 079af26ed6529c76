"""Docstrings on every public name and a type stub that declares each of them."""

import ast
import inspect
import pathlib

import texgrad

STUB = pathlib.Path(texgrad.__file__).with_name("__init__.pyi")


def test_version():
    assert texgrad.__version__.count(".") == 2


def test_every_public_name_has_a_docstring():
    for name in texgrad.__all__:
        if name == "__version__":
            continue
        value = getattr(texgrad, name)
        assert inspect.getdoc(value), name
        if inspect.isclass(value):
            for member, attribute in vars(value).items():
                if not member.startswith("_") and callable(attribute):
                    assert inspect.getdoc(attribute), f"{name}.{member}"


def test_stub_declares_every_public_name():
    tree = ast.parse(STUB.read_text())
    declared = {node.name for node in tree.body
                if isinstance(node, (ast.FunctionDef, ast.ClassDef))}
    declared |= {target.id for node in tree.body if isinstance(node, ast.AnnAssign)
                 for target in [node.target]}
    assert set(texgrad.__all__) <= declared
    assert (STUB.parent / "py.typed").exists()
