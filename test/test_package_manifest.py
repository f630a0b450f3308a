# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""package.xml declares every ROS package the code imports; CMakeLists.txt lets colcon test run pytest."""
import ast
import os
import re
from pathlib import Path
import xml.etree.ElementTree as ElementTree

ROOT = Path(__file__).resolve().parents[1]
#: Python modules that are ROS packages of the same name (rosdep keys), as far as this code goes.
ROS_PACKAGES = {'rclpy', 'rcl_interfaces', 'builtin_interfaces', 'std_msgs', 'sensor_msgs', 'geometry_msgs',
                'diagnostic_msgs', 'rosgraph_msgs', 'ament_index_python', 'launch', 'launch_ros'}
#: System rosdep keys this package declares, each one found in rosdistro's rosdep/python.yaml as published
#: (ros/rosdistro 8468e88, 2026-08-22): python3-rosbags-pip and python3-tqdm exist, so do the test tools'
#: (python3-mypy: ros/rosdistro 000730dc).
CHECKED_KEYS = {'python3-numpy', 'python3-scipy', 'python3-yaml', 'python3-matplotlib', 'python3-tqdm',
                'python3-rosbags-pip', 'python3-pytest', 'python3-pytest-timeout', 'python3-flake8', 'pydocstyle',
                'python3-mypy'}
#: Python packages the code or the tests use that have no key in that file (searched by name and by the
#: pip package a key installs): pip installs them from requirements/core.txt and requirements/test.txt.
NO_ROSDEP_KEY = {'mcap', 'lz4', 'zstandard', 'isal', 'pyarrow', 'dask', 'distributed', 'duckdb', 'polars',
                 'statsmodels'}
#: Test requirements only tools/test uses, not looked up as rosdep keys: pip installs them, and ``colcon test``
#: (plain pytest, no ``-n``) runs without them.
TOOLS_TEST_ONLY = {'pytest-xdist'}
#: Key of each requirement that has one (requirements/*.txt name -> rosdep key).
KEY_OF = {'numpy': 'python3-numpy', 'scipy': 'python3-scipy', 'pyyaml': 'python3-yaml',
          'matplotlib': 'python3-matplotlib', 'tqdm': 'python3-tqdm', 'rosbags': 'python3-rosbags-pip',
          'pytest': 'python3-pytest', 'pytest-timeout': 'python3-pytest-timeout', 'flake8': 'python3-flake8',
          'pydocstyle': 'pydocstyle', 'mypy': 'python3-mypy'}


def imported_top_level_modules():
    """Top-level module names imported anywhere in prsm_lube_ros/ and launch/."""
    names = set()
    for folder in ('prsm_lube_ros', 'launch'):
        for path in (ROOT / folder).rglob('*.py'):
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.Import):
                    names.update(alias.name.split('.')[0] for alias in node.names)
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names.add(node.module.split('.')[0])
    return names


def manifest_dependencies():
    """{tag: set of names} of package.xml."""
    tree = ElementTree.parse(ROOT / 'package.xml')
    found = {}
    for element in tree.getroot():
        if element.tag.endswith('depend'):
            found.setdefault(element.tag, set()).add(element.text.strip())
    return found


def test_every_imported_ros_package_is_declared():
    deps = manifest_dependencies()
    run = deps.get('exec_depend', set()) | deps.get('depend', set())
    missing = (imported_top_level_modules() & ROS_PACKAGES) - run
    assert not missing, f'imported but not in package.xml: {sorted(missing)}'
    system_keys = {name for name in set().union(*deps.values()) if name.startswith('python3-') or name in KEY_OF}
    assert system_keys <= CHECKED_KEYS, f'rosdep keys not checked to exist: {sorted(system_keys - CHECKED_KEYS)}'


def requirement_names(name: str) -> set:
    """Package names (lower case) of requirements/<name>."""
    names = set()
    for line in (ROOT / 'requirements' / name).read_text().splitlines():
        line = line.split('#')[0].strip()
        if line:
            names.add(re.split(r'[<>=\[ ;]', line, maxsplit=1)[0].lower())
    return names


def test_every_requirement_with_a_rosdep_key_is_declared_with_it():
    """rosdep installs what has a key (runtime: exec_depend, tests: test_depend); pip only the rest."""
    deps = manifest_dependencies()
    run = deps.get('exec_depend', set()) | deps.get('depend', set())
    for requirements, declared in (('core.txt', run), ('test.txt', deps.get('test_depend', set()))):
        names = requirement_names(requirements)
        unknown = names - set(KEY_OF) - NO_ROSDEP_KEY - TOOLS_TEST_ONLY
        assert not unknown, f'{requirements}: rosdep key not looked up for {sorted(unknown)}'
        missing = {KEY_OF[n] for n in names & set(KEY_OF)} - declared
        assert not missing, f'{requirements}: has a rosdep key but is not in package.xml: {sorted(missing)}'
    assert 'action_msgs' in deps.get('depend', set())          # action/Calibrate.action


def test_what_rosdep_cannot_install_is_in_the_pip_requirements():
    requirements = (ROOT / 'requirements' / 'core.txt').read_text().lower()
    for name in ('rosbags', 'mcap', 'tqdm', 'lz4', 'zstandard'):
        assert f'\n{name}' in requirements, name
    assert 'requirements/core.txt' in (ROOT / 'README.md').read_text()


def test_colcon_test_runs_the_pytest_suite():
    cmake = (ROOT / 'CMakeLists.txt').read_text()
    block = cmake[cmake.index('if(BUILD_TESTING)'):]
    block = block[:block.index('endif()')]
    assert 'find_package(ament_cmake_pytest REQUIRED)' in block
    assert 'ament_add_pytest_test(' in block and ' test' in block
    assert 'ament_cmake_pytest' in manifest_dependencies().get('test_depend', set())
    assert os.path.isdir(ROOT / 'test')


def test_setup_py_installs_the_requirement_files_and_ships_py_typed():
    """One dependency list: setup.py reads requirements/core.txt and test.txt, nothing of its own."""
    root = Path(__file__).resolve().parents[1]
    source = (root / 'setup.py').read_text()
    calls = {node.args[0].value for node in ast.walk(ast.parse(source))
             if isinstance(node, ast.Call) and getattr(node.func, 'id', '') == 'requirements'}
    assert calls == {'core', 'test'}
    assert "install_requires=requirements('core')" in source
    assert (root / 'prsm_lube_ros' / 'py.typed').is_file() and "'py.typed'" in source


def test_python_requires_is_the_version_the_code_is_checked_for_and_needs():
    """One answer: setup.py's python_requires is mypy's python_version, and the code uses what that version added."""
    import configparser
    root = Path(__file__).resolve().parents[1]
    config = configparser.ConfigParser()
    config.read(root / 'setup.cfg')
    checked = config['mypy']['python_version']
    assert re.search(r"python_requires='>=([0-9.]+)'", (root / 'setup.py').read_text()).group(1) == checked
    sources = '\n'.join(p.read_text() for p in (root / 'prsm_lube_ros').rglob('*.py'))
    assert checked == '3.11' and 'StrEnum' in sources and 'datetime.UTC' in sources    # both new in 3.11
