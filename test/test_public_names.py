# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Every module says what it offers: ``__all__`` lists exactly its public top-level names.

A public name is a function, class or assigned name without a leading
underscore defined at the top of the module (imported names are not its own).
Subpackage ``__init__`` modules that re-export may list names of their
submodules; every name listed must exist.
"""
import ast
import importlib
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'prsm_lube_ros'
ROS_FREE = [p for p in sorted(PACKAGE.rglob('*.py')) if 'nodes' not in p.parts and p.name != 'run.py']


def public_names(tree: ast.Module) -> set:
    """Names a module defines at its top level that do not start with an underscore."""
    names = []
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.append(node.name)
        elif isinstance(node, ast.Assign):
            names.extend(leaf.id for target in node.targets for leaf in ast.walk(target) if isinstance(leaf, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.append(node.target.id)
    return {name for name in names if not name.startswith('_')}


def declared_all(tree: ast.Module):
    """The literal ``__all__`` of a module, or None."""
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == '__all__' for t in node.targets):
            return ast.literal_eval(node.value)
    return None


@pytest.mark.parametrize('path', sorted(PACKAGE.rglob('*.py')), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_all_lists_the_public_names(path):
    tree = ast.parse(path.read_text())
    listed = declared_all(tree)
    own = public_names(tree)
    if path.name in ('__init__.py', '__main__.py'):
        assert listed is None or own <= set(listed), f'{path.name}: {sorted(own - set(listed or []))} not in __all__'
        return
    if not own:
        return
    assert listed is not None, f'{path}: no __all__'
    assert len(listed) == len(set(listed)), f'{path}: a name listed twice'
    assert set(listed) == own, (f'{path}: missing {sorted(own - set(listed))}, '
                                f'not defined here {sorted(set(listed) - own)}')


@pytest.mark.parametrize('path', [p for p in ROS_FREE if p.name == '__init__.py'],
                         ids=lambda p: str(p.relative_to(PACKAGE)))
def test_a_subpackages_all_names_exist(path):
    """Re-exports resolve (ROS-free subpackages; the nodes need a ROS environment)."""
    parts = path.relative_to(PACKAGE.parent).with_suffix('').parts[:-1]
    module = importlib.import_module('.'.join(parts))
    missing = [name for name in getattr(module, '__all__', []) if not hasattr(module, name)]
    assert not missing, f'{module.__name__}.__all__ names {missing}, which it does not have'


def test_the_check_catches_a_missing_name():
    tree = ast.parse("__all__ = ['a']\n\ndef a():\n    pass\n\n\ndef b():\n    pass\n")
    assert public_names(tree) - set(declared_all(tree)) == {'b'}
