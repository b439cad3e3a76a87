# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Build script for the formation_ros ament_python package."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'formation_ros'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml') + glob('config/*.rviz')),
        ('share/' + package_name + '/launch', glob('launch/*.launch.py')),
    ],
    install_requires=['setuptools'],
    extras_require={'test': ['pytest']},
    zip_safe=True,
    maintainer='The formation_ros authors',
    maintainer_email='formation-ros@example.com',
    description='Bounded decentralized formation control for mobile robots with limited sensing.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'formation_sim = formation_ros.tools.sim:main',
            'formation_report = formation_ros.tools.report:main',
            'formation_render = formation_ros.tools.render:main',
            'robot = formation_ros.nodes.entry:robot',
            'plant = formation_ros.nodes.entry:plant',
            'reference = formation_ros.nodes.entry:reference',
            'record = formation_ros.nodes.entry:record',
            'fleet = formation_ros.nodes.entry:fleet',
            'relay = formation_ros.nodes.entry:relay',
            'world = formation_ros.nodes.entry:world',
        ],
    },
)
