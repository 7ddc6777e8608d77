from glob import glob

from setuptools import find_packages, setup

package_name = 'rm_bringup'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={'rm_bringup': ['py.typed']},  # PEP 561: the package is typed
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
        ('share/' + package_name + '/launch', glob('launch/*.py')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='rm_ros2 developers',
    maintainer_email='rm-ros2@example.com',
    description='rm_ros2 bringup: robot configs, launch, runner, CLI, bags',
    license='Apache-2.0',
    extras_require={'test': ['pytest']},
    entry_points={
        'console_scripts': [
            'bringup = rm_bringup.bringup:main',
            'rmcli = rm_bringup.cli.main:main',
        ],
    },
)
