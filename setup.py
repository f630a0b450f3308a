# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""pip installation of prsm_lube_ros without colcon (core, command line, nodes).

In a ROS 2 workspace ``colcon build`` builds this package through
CMakeLists.txt (build type ament_cmake), which also generates the contract's
interfaces.  ``pip install .`` installs the same Python code for offline work
on recordings (``prsm-lube simulate | calibrate | assess | diagnose``) on a
machine without ROS; the nodes additionally need the generated interfaces.
"""
from glob import glob
from pathlib import Path

from setuptools import find_packages, setup

package_name = 'prsm_lube_ros'


def requirements(name):
    """The requirement lines of ``requirements/<name>.txt``: the one dependency list pip, CI and setup.py share."""
    text = (Path(__file__).resolve().parent / 'requirements' / f'{name}.txt').read_text()
    return [line.split('#')[0].strip() for line in text.splitlines() if line.split('#')[0].strip()]


setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
        ('share/' + package_name + '/launch', glob('launch/*.py')),
        ('share/' + package_name + '/msg', glob('msg/*.msg')),
        ('share/' + package_name + '/srv', glob('srv/*.srv')),
        ('share/' + package_name + '/action', glob('action/*.action')),
    ],
    package_data={package_name: ['py.typed']},
    python_requires='>=3.11',     # enum.StrEnum, datetime.UTC (the python_version mypy checks in setup.cfg)
    install_requires=requirements('core'),
    extras_require={'hardware': ['nidaqmx'], 'test': requirements('test')},
    zip_safe=True,
    maintainer='prsm_lube_ros developers',
    maintainer_email='prsm-lube@example.org',
    description='Lubrication assessment of planetary roller screws (theta_Oil) for ROS 2.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'prsm-lube = prsm_lube_ros.cli:main',
            'sensor_bridge = prsm_lube_ros.nodes.sensor_bridge:main',
            'sensor_bridge_managed = prsm_lube_ros.nodes.sensor_bridge:main_managed',
            'lubrication_estimator = prsm_lube_ros.nodes.lubrication_estimator:main',
        ],
    },
)
