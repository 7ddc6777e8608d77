"""PluginParams: typed parameters under the plugin's prefix; clear errors naming plugin and key."""

import enum

import pytest
import rclpy
from rclpy.parameter import Parameter
from rm_base.plugin import ParameterError, PluginParams

pytestmark = pytest.mark.ros


class Kinematics(enum.Enum):
    MECANUM = 'mecanum'
    OMNI = 'omni'


@pytest.fixture
def make_params(ros_context):
    nodes = []

    def make(**overrides):
        node = rclpy.create_node(
            'params_test', context=ros_context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )
        nodes.append(node)
        return PluginParams(node, 'chassis', 'rm_plugins/StandChassis')

    yield make
    for node in nodes:
        node.destroy_node()


def radius(params):
    return params.double('wheel_radius', description='wheel radius', unit='m', gt=0.0)


def test_value_from_config_under_the_dotted_prefix(make_params):
    params = make_params(**{'chassis.wheel_radius': 0.076})
    assert radius(params) == 0.076


def test_default_when_config_has_none(make_params):
    params = make_params()
    assert params.double('max_speed', 3.5, description='speed limit', unit='m/s') == 3.5


def test_an_integer_is_accepted_for_a_double(make_params):
    params = make_params(**{'chassis.wheel_radius': 1})
    value = radius(params)
    assert value == 1.0 and isinstance(value, float)


def test_when_required_parameter_is_missing_expect_error_naming_plugin_key_and_unit(make_params):
    params = make_params()
    with pytest.raises(
        ParameterError,
        match=r"^plugin 'chassis' \(rm_plugins/StandChassis\): parameter 'chassis.wheel_radius' "
        r'is required but not set \(double, m: wheel radius\)$',
    ) as info:
        radius(params)
    assert info.value.key == 'chassis.wheel_radius'
    assert info.value.plugin == 'chassis'


def test_when_value_has_the_wrong_type_expect_error_naming_key_and_types(make_params):
    params = make_params(**{'chassis.wheel_radius': 'big'})
    with pytest.raises(
        ParameterError,
        match=r"parameter 'chassis.wheel_radius' must be double \[m\]; got str 'big'",
    ):
        radius(params)


def test_when_value_is_out_of_bounds_expect_error_with_bound(make_params):
    params = make_params(**{'chassis.wheel_radius': -0.1})
    with pytest.raises(ParameterError, match=r"'chassis.wheel_radius' must be > 0.0, got -0.1"):
        radius(params)


def test_when_double_is_not_finite_expect_error(make_params):
    params = make_params(**{'chassis.wheel_radius': float('nan')})
    with pytest.raises(ParameterError, match='must be finite'):
        radius(params)


def test_integer_rejects_a_float(make_params):
    params = make_params(**{'chassis.wheel_count': 4.0})
    with pytest.raises(ParameterError, match=r"'chassis.wheel_count' must be integer; got float"):
        params.integer('wheel_count', description='wheels', ge=3)


def test_boolean_and_string(make_params):
    params = make_params(**{'chassis.invert': True, 'chassis.frame': 'base_link'})
    assert params.boolean('invert', False, description='invert') is True
    assert params.string('frame', description='frame') == 'base_link'


def test_string_choices(make_params):
    params = make_params(**{'chassis.mode': 'fast'})
    with pytest.raises(ParameterError, match=r"must be one of slow, normal, got 'fast'"):
        params.string('mode', 'slow', description='mode', choices=['slow', 'normal'])


def test_choice_maps_a_name_to_an_enum_member_case_insensitively(make_params):
    params = make_params(**{'chassis.kinematics': 'Omni'})
    assert params.choice('kinematics', Kinematics, Kinematics.MECANUM, description='k') is (
        Kinematics.OMNI
    )


def test_choice_with_an_unknown_name_lists_the_options(make_params):
    params = make_params(**{'chassis.kinematics': 'tank'})
    with pytest.raises(ParameterError, match=r"must be one of mecanum, omni, got 'tank'"):
        params.choice('kinematics', Kinematics, Kinematics.MECANUM, description='k')


def test_arrays_come_back_as_tuples(make_params):
    params = make_params(**{
        'chassis.joints': ['lf', 'rf', 'lb', 'rb'],
        'chassis.gains': [1, 2],  # an integer array is fine for a double array
    })
    assert params.string_array('joints', description='j', length=4) == ('lf', 'rf', 'lb', 'rb')
    gains = params.double_array('gains', description='g')
    assert gains == (1.0, 2.0)
    assert all(isinstance(g, float) for g in gains)


def test_array_length_is_checked(make_params):
    params = make_params(**{'chassis.joints': ['lf', 'rf']})
    with pytest.raises(ParameterError, match=r"'chassis\.joints' must have 4 entries, has 2"):
        params.string_array('joints', description='j', length=4)


def test_array_entries_are_bounds_checked(make_params):
    params = make_params(**{'chassis.radii': [0.07, -1.0]})
    with pytest.raises(ParameterError, match=r'entry \[1\] must be > 0.0, got -1.0'):
        params.double_array('radii', description='r', gt=0.0)


def test_unique_string_array_rejects_duplicates(make_params):
    params = make_params(**{'chassis.joints': ['lf', 'lf']})
    with pytest.raises(ParameterError, match='duplicate entries: lf'):
        params.string_array('joints', description='j', unique=True)


def test_when_a_scalar_is_given_for_an_array_expect_error(make_params):
    params = make_params(**{'chassis.joints': 'lf'})
    with pytest.raises(ParameterError, match=r"must be string\[\]; got str 'lf'"):
        params.string_array('joints', description='j')


def test_declared_parameter_has_description_unit_and_is_read_only(make_params):
    params = make_params(**{'chassis.wheel_radius': 0.076})
    radius(params)
    descriptor = params._node.describe_parameter('chassis.wheel_radius')
    assert descriptor.description == 'wheel radius [m]'
    assert descriptor.additional_constraints == (
        'type: double; unit: m; > 0.0; required; read at start-up: a change needs a restart'
    )
    assert descriptor.read_only
    result = params._node.set_parameters([Parameter('chassis.wheel_radius', value=0.1)])[0]
    assert not result.successful


def test_declaring_the_same_key_twice_is_an_error(make_params):
    params = make_params()
    params.double('x', 1.0, description='x')
    with pytest.raises(ParameterError, match=r"'chassis\.x' cannot be declared"):
        params.double('x', 1.0, description='x')


def test_a_default_of_the_wrong_type_is_a_programming_error(make_params):
    params = make_params()
    with pytest.raises(TypeError, match=r"default of parameter 'chassis\.x' is not a valid double"):
        params.double('x', 'one', description='x')


def test_node_level_parameters_have_no_prefix_and_no_plugin_in_the_message(ros_context):
    node = rclpy.create_node('params_test', context=ros_context)
    try:
        params = PluginParams(node, '', prefix='')
        with pytest.raises(ParameterError, match=r"^parameter 'plugins' is required"):
            params.string_array('plugins', description='plugins')
    finally:
        node.destroy_node()


def test_a_loop_pid_is_positional_by_default_and_incremental_with_its_td_when_asked(make_params):
    from rm_base.control import IncrementalPidConfig, PidGains, TdParams
    from rm_base.plugin.pid_params import loop_pid

    gains = PidGains(kp=2.0, ki=0.5, kd=0.1, output_limit=3.0, integral_limit=1.0,
                     angle_mode=True)
    assert loop_pid(make_params(), 'follow.pid', gains, setpoint_unit='rad') is gains
    params = make_params(**{'chassis.follow.pid.form': 'incremental',
                            'chassis.follow.pid.td_acceleration_limit': 40.0})
    config = loop_pid(params, 'follow.pid', gains, setpoint_unit='rad')
    assert isinstance(config, IncrementalPidConfig)
    assert (config.gains.kp, config.gains.ki, config.gains.kd) == (2.0, 0.5, 0.1)
    assert (config.output_limit, config.angle_mode) == (3.0, True)
    assert config.setpoint_td == TdParams(40.0, None)


@pytest.mark.parametrize(
    ('overrides', 'message'),
    [
        ({'form': 'velocity'}, r"'chassis.follow.pid.form' must be one of positional, incremental"),
        ({'td_acceleration_limit': 40.0}, 'applies to the incremental form only'),
        ({'form': 'incremental', 'td_filter_factor': 0.01},
         'td_filter_factor.* needs td_acceleration_limit > 0'),
    ],
)
def test_a_bad_loop_pid_form_is_refused_naming_the_key(make_params, overrides, message):
    from rm_base.control import PidGains
    from rm_base.plugin.pid_params import loop_pid

    params = make_params(**{f'chassis.follow.pid.{k}': v for k, v in overrides.items()})
    with pytest.raises(ParameterError, match=message):
        loop_pid(params, 'follow.pid', PidGains(kp=1.0, angle_mode=True), setpoint_unit='rad')
