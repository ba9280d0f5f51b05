"""The type stubs against the module they describe: raypack/_raypack.pyi and py.typed ship beside
the compiled module; the stubs name every public name of raypack.__all__ and nothing else, every
method and property of its classes, and each parameter with the name, kind and default that
inspect.signature reads from the binding (python/text_signatures.h). A binding added, renamed or
given another default without its stub fails here."""

import ast
import inspect
import math
import types
from pathlib import Path

import pytest

import raypack
from raypack import _raypack

PACKAGE = Path(raypack.__file__).parent
NO_DEFAULT = inspect.Parameter.empty
OUR_DUNDERS = {"__init__", "__repr__"}  # the special methods the bindings define


def stub_module():
    return ast.parse((PACKAGE / "_raypack.pyi").read_text())


def public(name):
    return not name.startswith("_") or name in OUR_DUNDERS


def stub_parameters(function):
    """[(name, kind, default)] of a stub's def, defaults evaluated (NO_DEFAULT where none)."""
    a = function.args
    value = lambda node: NO_DEFAULT if node is None else eval(ast.unparse(node), {"math": math})  # noqa: E731
    positional = a.posonlyargs + a.args
    defaults = [None] * (len(positional) - len(a.defaults)) + a.defaults
    out = [(p.arg, inspect.Parameter.POSITIONAL_ONLY, value(d)) for p, d in zip(a.posonlyargs, defaults)]
    out += [(p.arg, inspect.Parameter.POSITIONAL_OR_KEYWORD, value(d))
            for p, d in zip(a.args, defaults[len(a.posonlyargs):])]
    out += [(p.arg, inspect.Parameter.KEYWORD_ONLY, value(d)) for p, d in zip(a.kwonlyargs, a.kw_defaults)]
    assert a.vararg is None and a.kwarg is None, function.name
    return out


def decorators(function):
    return {ast.unparse(d) for d in function.decorator_list}


def stub_members(body):
    """{name: [defs]} of the public functions in a stub body (overloads: several defs), and the
    set of public names it assigns or declares."""
    functions, names = {}, set()
    for node in body:
        if isinstance(node, ast.FunctionDef) and public(node.name):
            functions.setdefault(node.name, []).append(node)
        elif isinstance(node, ast.ClassDef) and public(node.name):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and (public(node.target.id) or node.target.id == "__version__"):
            names.add(node.target.id)
    return functions, names


def check_signature(where, runtime, stubs):
    """Each stub def (each overload) has the runtime's parameters: names and kinds, and the same
    default wherever the stub gives one (an overload may leave one out, as render's aovs=True)."""
    signature = inspect.signature(runtime)
    assert "handle" not in str(signature), where
    got = [(p.name, p.kind, p.default) for p in signature.parameters.values()]
    for stub in stubs:
        want = stub_parameters(stub)
        assert [(n, k) for n, k, _ in got] == [(n, k) for n, k, _ in want], where
        for (name, _, have), (_, _, default) in zip(got, want):
            if default is not NO_DEFAULT or len(stubs) == 1:
                assert have == default or (have != have and default != default), (where, name, have, default)


def test_the_stubs_ship_beside_the_module():
    assert (PACKAGE / "py.typed").is_file()
    assert (PACKAGE / "_raypack.pyi").is_file()
    assert Path(_raypack.__file__).parent == PACKAGE


def test_the_stubs_name_every_public_name_and_nothing_else():
    functions, names = stub_members(stub_module().body)
    assert set(functions) | names == set(raypack.__all__)
    compiled = {name for name in dir(_raypack) if not name.startswith("_")} | {"__version__"}
    assert compiled == set(raypack.__all__)  # what the module binds, the package exports


def test_every_function_has_the_stubs_signature():
    functions, _ = stub_members(stub_module().body)
    for name, stubs in functions.items():
        check_signature(name, getattr(raypack, name), stubs)


@pytest.mark.parametrize("cls", [raypack.Scene, raypack.Backend])
def test_every_method_and_property_has_its_stub(cls):
    stub = next(node for node in stub_module().body if isinstance(node, ast.ClassDef) and node.name == cls.__name__)
    functions, _ = stub_members(stub.body)
    # pybind11's refusal to construct a class it has no constructor for is a slot wrapper: not ours.
    runtime = {name: value for name, value in vars(cls).items()
               if public(name) and not isinstance(value, types.WrapperDescriptorType)}
    assert set(functions) == set(runtime), cls
    for name, value in runtime.items():
        stubs = functions[name]
        if isinstance(value, property):
            assert all(decorators(s) == {"property"} for s in stubs), (cls, name)
            continue
        static = isinstance(value, staticmethod)
        assert all(("staticmethod" in decorators(s)) == static for s in stubs), (cls, name)
        check_signature(f"{cls.__name__}.{name}", getattr(cls, name), stubs)


def test_inspect_reads_every_public_callable():
    """Classes that Python code constructs show their constructor's parameters."""
    assert str(inspect.signature(raypack.Backend)).startswith("(name, scene, variant='default', *,")
    assert str(inspect.signature(raypack.Scene)) == "()"
    assert str(inspect.signature(raypack.Backend.intersect)) == (
        "(self, origins, directions=None, tnear=0.0, tfar=inf, coherent=False, *, mask=None, invalid='warn', "
        "normals=True, threads=0)")
    assert str(inspect.signature(raypack.Backend(
        "embree", raypack.Scene.from_arrays([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])).occluded)) == (
        "(origins, directions=None, tnear=0.0, tfar=inf, coherent=False, *, mask=None, invalid='warn', threads=0)")
    assert str(inspect.signature(raypack.Scene.add_quadric)) == (
        "(self, coefficients, clip_min, clip_max, *, center=(0.0, 0.0, 0.0))")
    assert raypack.Backend.intersect.__doc__.startswith("Closest hits:")  # the signature line is not in the text
