# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""package.xml declares every ROS package the code imports; CMakeLists.txt lets colcon test run pytest."""
import ast
import os
from pathlib import Path
import xml.etree.ElementTree as ElementTree

ROOT = Path(__file__).resolve().parents[1]
#: Python modules that are ROS packages of the same name (rosdep keys), as far as this code goes.
ROS_PACKAGES = {'rclpy', 'rcl_interfaces', 'builtin_interfaces', 'std_msgs', 'sensor_msgs', 'geometry_msgs',
                'diagnostic_msgs', 'rosgraph_msgs', 'ament_index_python', 'launch', 'launch_ros'}
#: System rosdep keys this package may declare: each one looked up in rosdistro's rosdep/python.yaml (2026).
#: Anything else (rosbags, mcap, tqdm, lz4, zstandard have no key) is installed with pip from
#: requirements/core.txt, as the README and package.xml say.
CHECKED_KEYS = {'python3-numpy', 'python3-scipy', 'python3-yaml', 'python3-matplotlib', 'python3-pytest'}


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
    system_keys = {name for name in set().union(*deps.values()) if name.startswith('python3-')}
    assert system_keys <= CHECKED_KEYS, f'rosdep keys not checked to exist: {sorted(system_keys - CHECKED_KEYS)}'


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
