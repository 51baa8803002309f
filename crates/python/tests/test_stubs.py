"""The type stubs (`_admittance.pyi`) name exactly what the compiled module exports: the same
classes and functions, and in each class the same public methods and properties, so that a
name added to (or removed from) the bindings without its stub fails here. The package
re-exports the module's names without listing them again."""

import ast
import pathlib

import admittance
from admittance import _admittance

STUBS = pathlib.Path(admittance.__file__).with_name("_admittance.pyi")


def stub_tree():
    return ast.parse(STUBS.read_text())


def stub_constants():
    """Top-level annotated names of the stubs (``DEFAULT_NODES: int``), but ``__version__``."""
    return {
        node.target.id
        for node in stub_tree().body
        if isinstance(node, ast.AnnAssign) and not node.target.id.startswith("_")
    }


def module_constants():
    return {
        name
        for name, value in vars(_admittance).items()
        if not name.startswith("_") and not isinstance(value, type) and not callable(value)
    }


def stub_names():
    """Top-level classes and functions of the stubs, with each class's methods."""
    classes, functions = {}, set()
    for node in stub_tree().body:
        if isinstance(node, ast.ClassDef):
            classes[node.name] = {
                item.name
                for item in node.body
                if isinstance(item, ast.FunctionDef) and not item.name.startswith("_")
            }
        elif isinstance(node, ast.FunctionDef):
            functions.add(node.name)
    return classes, functions


def module_names():
    classes, functions = {}, set()
    for name, value in vars(_admittance).items():
        if name.startswith("_"):
            continue
        if isinstance(value, type):
            classes[name] = {
                attr
                for attr in vars(value)
                if not attr.startswith("_") and not issubclass(value, BaseException)
            }
        elif callable(value):
            functions.add(name)
    return classes, functions


def test_the_stubs_name_every_class_and_function_of_the_module():
    stub_classes, stub_functions = stub_names()
    classes, functions = module_names()
    assert sorted(stub_classes) == sorted(classes)
    assert sorted(stub_functions) == sorted(functions)
    assert sorted(stub_constants()) == sorted(module_constants())


def test_the_stubs_name_every_method_and_property():
    stub_classes, _ = stub_names()
    classes, _ = module_names()
    for name, members in classes.items():
        if issubclass(getattr(_admittance, name), BaseException):
            continue
        assert sorted(stub_classes[name]) == sorted(members), name


def test_the_package_exports_the_module_once():
    classes, functions = module_names()
    assert sorted(admittance.__all__) == sorted(
        [*classes, *functions, *module_constants(), "__version__"]
    )
    for name in admittance.__all__:
        assert getattr(admittance, name) is getattr(_admittance, name)

