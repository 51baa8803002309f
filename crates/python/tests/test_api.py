"""The public surface: the names of the issue's contract exist, every public name and member
has a docstring and a type stub, and the package is typed (py.typed)."""

import ast
import inspect
import pathlib

import admittance as adm

PACKAGE = pathlib.Path(adm.__file__).parent
CONTRACT = {
    "Model", "rnea", "crba", "gravity", "coriolis", "tip_pose", "tip_jacobian", "aba",
    "MomentumObserver", "LearnedObserver", "HybridObserver",
    "NeuralController", "PdController", "ComputedTorqueController",
    "Admittance", "train", "load_network", "run",
    "identify", "Identification", "load_identification",
}


def public_members(obj):
    return [n for n, _ in inspect.getmembers(obj) if not n.startswith("_")]


def test_contract_names_are_exported():
    assert CONTRACT <= set(adm.__all__)
    for name in adm.__all__:
        assert hasattr(adm, name), name
    assert adm.__version__.count(".") == 2


def test_every_public_name_and_member_has_a_docstring():
    missing = []
    for name in adm.__all__:
        obj = getattr(adm, name)
        if name == "__version__":
            continue
        if not (obj.__doc__ or "").strip():
            missing.append(name)
        if inspect.isclass(obj):
            for member in public_members(obj):
                if issubclass(obj, BaseException) and hasattr(BaseException, member):
                    continue  # inherited from Python's exceptions
                if not (getattr(obj, member).__doc__ or "").strip():
                    missing.append(f"{name}.{member}")
    assert not missing, missing


def test_stubs_declare_every_public_name_and_member():
    stub = ast.parse((PACKAGE / "_admittance.pyi").read_text())
    declared = {}
    for node in stub.body:
        if isinstance(node, ast.ClassDef):
            declared[node.name] = {
                n.name for n in node.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
            }
        elif isinstance(node, ast.FunctionDef):
            declared[node.name] = set()
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            declared[node.target.id] = set()
    missing = []
    for name in adm.__all__:
        if name not in declared:
            missing.append(name)
            continue
        obj = getattr(adm, name)
        if inspect.isclass(obj):
            # Members declared on the class itself or inherited from a stubbed base.
            bases = [b.__name__ for b in obj.__mro__[1:] if b.__name__ in declared]
            have = declared[name].union(*(declared[b] for b in bases))
            for member in public_members(obj):
                if issubclass(obj, BaseException) and hasattr(BaseException, member):
                    continue  # inherited from Python's exceptions
                if member not in have:
                    missing.append(f"{name}.{member}")
    assert not missing, missing
    assert (PACKAGE / "py.typed").exists()


def test_keyword_signatures_match_the_contract(baxter):
    # The contract's keyword names, called by keyword.
    m = adm.Model.from_urdf(path=str(baxter_path()), base="base", tip="left_hand")
    adm.MomentumObserver(m, gain=50.0)
    adm.NeuralController(m, config=None)
    adm.Admittance(m, damping=3.0, stiffness=5.0, mass=None, rho=0.95, bound=None)


def baxter_path():
    from conftest import BAXTER
    return BAXTER
