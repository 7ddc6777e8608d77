from setuptools import find_packages, setup

package_name = 'rm_base'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={'rm_base': ['py.typed']},  # PEP 561: the package is typed
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='rm_ros2 developers',
    maintainer_email='rm-ros2@example.com',
    description='rm_ros2 framework: plugins, host, control maths, CAN layer, bridge, simulator',
    license='Apache-2.0',
    extras_require={'test': ['pytest', 'hypothesis']},
    entry_points={
        'console_scripts': [
            'can_bridge = rm_base.bridge.main:main',
            'rm_robot = rm_base.host.main:main',
            'rm_sim = rm_base.bridge.sim_process:main',
        ],
        # The simulated CAN interface: can.Bus(interface='rm_sim', channel=...).
        'can.interface': [
            'rm_sim = rm_base.sim.bus:SimBus',
            'rm_sim_socket = rm_base.sim.socket_bus:SimSocketBus',
        ],
    },
)
