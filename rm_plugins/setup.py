from setuptools import find_packages, setup

package_name = 'rm_plugins'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={'rm_plugins': ['py.typed'], 'rm_plugins.manual': ['default_mapping.yaml']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml', 'plugins.xml']),
        # pluginlib-style export: the marker's content is plugins.xml's path in the prefix.
        (
            'share/ament_index/resource_index/rm_base__pluginlib__plugin',
            ['resource/rm_base__pluginlib__plugin/' + package_name],
        ),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='rm_ros2 developers',
    maintainer_email='rm-ros2@example.com',
    description='rm_ros2 mechanism plugins: chassis, gimbal, shooter, gpio, imu, referee, manual',
    license='Apache-2.0',
    extras_require={'test': ['pytest']},
    entry_points={
        'console_scripts': [],
    },
)
