"""The type stubs (gradel/gradel.pyi) describe the compiled module as it is: mypy's stubtest
finds names missing on either side, and the parameters of every function and method (names,
order, keyword-only marker) are compared with the signatures pybind11 writes into the
docstrings."""
import ast
import os
import subprocess
import sys

import pytest

import gradel
import gradel.gradel as native

STUB = os.path.join(os.path.dirname(gradel.__file__), "gradel.pyi")


def split_top_level(text):
    parts, depth, cur = [], 0, ""
    for ch in text:
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(cur.strip())
            cur = ""
        else:
            cur += ch
    if cur.strip():
        parts.append(cur.strip())
    return parts


def runtime_params(obj):
    """['path', '*', 'format', ...] from pybind11's 'name(a: T, *, b: T = x) -> R' line."""
    line = obj.__doc__.splitlines()[0]
    inner = line[line.index("(") + 1: line.rindex(") ->")]
    names = [p.split(":")[0].split("=")[0].strip() for p in split_top_level(inner)]
    return [n for n in names if n != "self"]


def stub_params(fn):
    a = fn.args
    names = [x.arg for x in a.posonlyargs + a.args if x.arg != "self"]
    if a.kwonlyargs:
        names += ["*"] + [x.arg for x in a.kwonlyargs]
    if a.kwarg:
        names.append("**" + a.kwarg.arg)
    return names


def stub_functions():
    tree = ast.parse(open(STUB).read())
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            yield node.name, getattr(native, node.name, None), node
        elif isinstance(node, ast.ClassDef) and hasattr(native, node.name):
            cls = getattr(native, node.name)
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    decorators = {d.id for d in item.decorator_list if isinstance(d, ast.Name)}
                    if "property" in decorators:
                        assert isinstance(cls.__dict__[item.name], property), f"{node.name}.{item.name}"
                    else:
                        yield f"{node.name}.{item.name}", getattr(cls, item.name, None), item


@pytest.mark.parametrize("name,obj,fn", list(stub_functions()), ids=lambda x: x if isinstance(x, str) else "")
def test_stub_parameters_match_the_module(name, obj, fn):
    assert obj is not None, f"{name} is in the stub, not in the module"
    assert stub_params(fn) == runtime_params(obj), name


def test_every_public_name_has_a_stub():
    tree = ast.parse(open(STUB).read())
    stubbed = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    public = {n for n in dir(native) if not n.startswith("_")}
    assert public <= stubbed, public - stubbed
    classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}
    for cname in ("Body", "Simulation"):
        members = {i.name for i in classes[cname].body if isinstance(i, ast.FunctionDef)}
        runtime = {n for n in vars(getattr(native, cname)) if not n.startswith("_")}
        assert runtime <= members, (cname, runtime - members)


def test_mypy_stubtest(tmp_path):
    pytest.importorskip("mypy", reason="python3-mypy (scripts/packages/python.txt)")
    site = os.path.dirname(os.path.dirname(os.path.abspath(gradel.__file__)))  # the folder gradel was imported from
    allow = os.path.join(os.path.dirname(__file__), "stubtest_allowlist.txt")
    r = subprocess.run([sys.executable, "-m", "mypy.stubtest", "gradel.gradel", "--allowlist", allow],
                       capture_output=True, text=True, cwd=tmp_path, env={**os.environ, "MYPY_CACHE_DIR": str(tmp_path), "PYTHONPATH": site})
    assert r.returncode == 0, r.stdout + r.stderr
