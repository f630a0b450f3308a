# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The package's layers import only downward, and only nodes/ and the ``run`` command touch ROS.

Every import of every module is read with :mod:`ast` (module-level and the
lazy ones inside functions), resolved to the package's subpackage, and checked
against the layer table below.  The table is the architecture the README's
module map describes; a change that needs an upward import must change it here,
visibly.
"""
import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'prsm_lube_ros'

#: Top-level modules that form the base layer (they import nothing of the package but each other).
BASE = {'errors', 'contract', 'validation', 'config_file', 'figures', 'condition_figures', 'atomic_file', 'input_file',
        'stopping', '__init__'}
#: Which layers each layer may import (base is always allowed).
ALLOWED = {
    'base': set(),
    'physics': set(),
    'recording': set(),
    'estimation': {'physics', 'recording'},
    'diagnosis': {'physics', 'recording', 'estimation'},
    'fleet': {'physics', 'recording', 'estimation'},
    'simulation': {'physics', 'recording', 'estimation'},
    'experiments': {'physics', 'recording', 'estimation', 'diagnosis', 'simulation', 'fleet'},
    'nodes': {'physics', 'recording', 'estimation', 'simulation', 'fleet', 'msg', 'srv', 'action'},
    'cli': {'physics', 'recording', 'estimation', 'diagnosis', 'simulation', 'experiments', 'nodes', 'fleet'},
}
#: ROS Python packages (the generated interfaces are checked as the layers 'msg' and 'srv').
ROS_MODULES = {'rclpy', 'rcl_interfaces', 'builtin_interfaces', 'std_msgs', 'sensor_msgs', 'geometry_msgs',
               'diagnostic_msgs', 'rosgraph_msgs', 'launch', 'launch_ros', 'ament_index_python', 'lifecycle_msgs'}


def layer_of(parts):
    """Layer of a module given its path parts below the package."""
    if len(parts) == 1:
        return 'base' if parts[0] in BASE else parts[0]
    return parts[0]


def modules():
    for path in sorted(PACKAGE.rglob('*.py')):
        parts = path.relative_to(PACKAGE).with_suffix('').parts
        yield path, parts


def imports(path, parts):
    """(line, package-relative target parts or None, top-level external name or None) of each import."""
    tree = ast.parse(path.read_text())
    package_parts = list(parts[:-1]) if parts[-1] != '__init__' else list(parts[:-1])
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                top = alias.name.split('.')[0]
                if top == 'prsm_lube_ros':
                    yield node.lineno, alias.name.split('.')[1:], None
                else:
                    yield node.lineno, None, top
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0:
                top = (node.module or '').split('.')[0]
                if top == 'prsm_lube_ros':
                    base = node.module.split('.')[1:]
                    for alias in node.names:
                        yield node.lineno, base or [alias.name], None
                else:
                    yield node.lineno, None, top
                continue
            base = package_parts[:len(package_parts) - (node.level - 1)]
            target = base + (node.module.split('.') if node.module else [])
            if not target:  # from . import x at the package root
                for alias in node.names:
                    yield node.lineno, [alias.name], None
            else:
                yield node.lineno, target, None


def test_every_layer_imports_only_downward():
    wrong = []
    for path, parts in modules():
        layer = layer_of(parts)
        assert layer in ALLOWED, f'{path}: subpackage {layer!r} is not in the layer table'
        for line, target, _ in imports(path, parts):
            if target is None:
                continue
            other = layer_of(target)
            if other in ('base', layer) or other in ALLOWED[layer]:
                continue
            wrong.append(f'{path.relative_to(PACKAGE.parent)}:{line}: {layer} imports {".".join(target)} ({other})')
    assert not wrong, 'upward or sideways imports:\n' + '\n'.join(wrong)


def test_the_base_layer_imports_nothing_of_the_package_above_it():
    for path, parts in modules():
        if layer_of(parts) != 'base' or parts == ('__init__',):
            continue
        for line, target, _ in imports(path, parts):
            assert target is None or layer_of(target) == 'base', f'{path}:{line} imports {target}'


def test_only_nodes_and_the_run_command_import_ros():
    wrong = []
    for path, parts in modules():
        if parts[0] == 'nodes' or parts == ('cli', 'run'):
            continue
        for line, target, external in imports(path, parts):
            if external in ROS_MODULES or (target and target[0] in ('msg', 'srv')):
                wrong.append(f'{path.relative_to(PACKAGE.parent)}:{line}')
    assert not wrong, 'ROS imported outside nodes/: ' + ', '.join(wrong)


@pytest.mark.parametrize('subpackage', sorted(p.name for p in PACKAGE.iterdir()
                                              if p.is_dir() and (p / '__init__.py').is_file()))
def test_every_subpackage_says_what_it_owns_and_what_it_may_import(subpackage):
    doc = ast.get_docstring(ast.parse((PACKAGE / subpackage / '__init__.py').read_text())) or ''
    assert 'Owns' in doc or 'owns' in doc, f'{subpackage}: the docstring does not say what it owns'
    assert 'import' in doc, f'{subpackage}: the docstring does not say what it may import'


def test_the_checker_sees_an_upward_import(tmp_path):
    """The test above can fail: a physics module importing estimation is caught."""
    fake = tmp_path / 'prsm_lube_ros' / 'physics'
    fake.mkdir(parents=True)
    (fake / 'bad.py').write_text('from ..estimation.calibration import Calibration\n')
    found = [target for _, target, _ in imports(fake / 'bad.py', ('physics', 'bad'))]
    assert found == [['estimation', 'calibration']]
    assert layer_of(found[0]) not in ALLOWED['physics']


def _runtime_graph():
    """Module -> modules it imports when it is imported: module-level imports outside ``if TYPE_CHECKING``.

    A package ``__init__`` that imports its modules by name (``importlib.import_module(f'{__name__}.{id}')``,
    the effect registries) imports every module of its folder.
    """
    graph = {}
    for path, parts in modules():
        name = '.'.join(parts[:-1] if parts[-1] == '__init__' else parts)
        tree = ast.parse(path.read_text())
        top = [node for node in tree.body
               if not (isinstance(node, ast.If) and 'TYPE_CHECKING' in ast.unparse(node.test))]
        shallow = ast.Module(body=top, type_ignores=[])
        targets = set()
        for _, target, _ in imports_of_tree(shallow, parts):
            if target:
                targets.add('.'.join(target))
        if parts[-1] == '__init__' and 'import_module' in path.read_text():
            targets.update('.'.join((*parts[:-1], p.stem)) for p in path.parent.glob('*.py') if p.stem != '__init__')
        graph[name] = targets
    known = set(graph)
    # a target may name an object inside a module (from .x import Name): keep the longest known module prefix
    resolved = {}
    for name, targets in graph.items():
        out = set()
        for target in targets:
            pieces = target.split('.')
            while pieces and '.'.join(pieces) not in known:
                pieces.pop()
            if pieces and '.'.join(pieces) != name:
                out.add('.'.join(pieces))
        resolved[name] = out
    return resolved


def imports_of_tree(tree, parts):
    """:func:`imports` of an already parsed (and possibly trimmed) module tree."""
    class _Path:
        def read_text(self):
            return ast.unparse(tree)
    return imports(_Path(), parts)


def _circles(graph):
    """Strongly connected groups of more than one module (Tarjan)."""
    index, low, stack, on, found, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                found.append(sorted(group))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_circle_between_modules():
    """Importing a module never needs a module that is itself still being imported (its import order by luck).

    Package ``__init__`` modules are left out as targets of their own submodules' imports (Python runs a
    package's ``__init__`` first by design); every other circle fails.
    """
    graph = _runtime_graph()
    for name in graph:      # a submodule importing its own package's __init__ is no circle
        graph[name] = {t for t in graph[name] if not name.startswith(t + '.')}
    assert _circles(graph) == []


def test_the_circle_check_sees_a_circle():
    assert _circles({'a': {'b'}, 'b': {'c'}, 'c': {'a'}, 'd': {'a'}}) == [['a', 'b', 'c']]
