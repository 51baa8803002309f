// A ros2_control chainable controller that runs the admittance loop's external-torque
// observer at the controller manager's rate and exports its estimate as a virtual
// force-torque sensor: state interfaces `<controller name>/<sensor>/force.x ... torque.z`,
// which ros2_controllers' admittance_controller reads with `ft_sensor.name:
// <controller name>/<sensor>` (adm_estimator.yaml beside this file). The robot then
// becomes compliant without a force-torque sensor.
//
// NOT BUILT HERE: it needs a ROS 2 install (Jazzy or later: state interfaces exported by a
// chainable controller, `on_export_state_interfaces`) with ros2_control and
// ros2_controllers; CI builds only tests/cpp/loop_test.cpp, which makes the same calls
// against the simulated arm. Build it as the colcon package of this folder (CMakeLists.txt,
// package.xml), after `cargo build --release -p admittance-ffi`.
//
// What it claims: `<joint>/position` and `<joint>/effort` state interfaces of every joint
// in `joints` (effort: the measured joint torque, which the learned observer was trained
// on); no command interface. What it exports: the wrench the environment applies to the
// hand, in the axes of the deployment's `[arm] tip` link (AdmOutput::wrench_tip), which is
// admittance_controller's `ft_sensor.frame.id`.

#include <array>
#include <cstring>
#include <string>
#include <vector>

#include "admittance.h"
#include "controller_interface/chainable_controller_interface.hpp"
#include "hardware_interface/handle.hpp"
#include "pluginlib/class_list_macros.hpp"

namespace admittance_ffi_examples {

using controller_interface::CallbackReturn;
using controller_interface::InterfaceConfiguration;
using controller_interface::interface_configuration_type;
using controller_interface::return_type;

class AdmittanceEstimator : public controller_interface::ChainableControllerInterface {
public:
  ~AdmittanceEstimator() override { adm_destroy(loop_); }

  CallbackReturn on_init() override {
    auto_declare<std::vector<std::string>>("joints", {});
    auto_declare<std::string>("deployment_path", "");
    auto_declare<std::string>("sensor_name", "virtual_ft");
    return CallbackReturn::SUCCESS;
  }

  // Not real-time: reads the deployment folder (admittance deploy), allocates.
  CallbackReturn on_configure(const rclcpp_lifecycle::State &) override {
    joints_ = get_node()->get_parameter("joints").as_string_array();
    deployment_ = get_node()->get_parameter("deployment_path").as_string();
    sensor_ = get_node()->get_parameter("sensor_name").as_string();
    AdmConfig config;
    std::memset(&config, 0, sizeof config);
    config.abi_version = ADM_ABI_VERSION;
    config.n_joints = static_cast<uint32_t>(joints_.size());
    config.deployment_path = deployment_.c_str();
    config.flags = ADM_CONFIG_WRENCH;
    adm_destroy(loop_);
    loop_ = adm_create(&config);
    if (!loop_) {
      char msg[1024];
      adm_last_error(nullptr, msg, sizeof msg);
      RCLCPP_ERROR(get_node()->get_logger(), "adm_create: %s", msg);
      return CallbackReturn::ERROR;
    }
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_activate(const rclcpp_lifecycle::State &) override {
    wrench_.fill(0.0);
    time_ = 0.0;
    return CallbackReturn::SUCCESS;
  }

  InterfaceConfiguration command_interface_configuration() const override {
    return {interface_configuration_type::NONE, {}};
  }

  // Ordered joint by joint: position, then effort.
  InterfaceConfiguration state_interface_configuration() const override {
    std::vector<std::string> names;
    for (const auto &j : joints_) {
      names.push_back(j + "/position");
      names.push_back(j + "/effort");
    }
    return {interface_configuration_type::INDIVIDUAL, names};
  }

protected:
  // The virtual sensor: `<controller name>/<sensor>/force.x` ... `torque.z`, pointing into
  // wrench_ (which lives as long as the controller).
  std::vector<hardware_interface::StateInterface> on_export_state_interfaces() override {
    static const char *axes[6] = {"force.x", "force.y", "force.z",
                                  "torque.x", "torque.y", "torque.z"};
    std::vector<hardware_interface::StateInterface> out;
    for (int i = 0; i < 6; ++i) {
      out.emplace_back(get_node()->get_name(), sensor_ + "/" + axes[i], &wrench_[i]);
    }
    return out;
  }

  // No reference interfaces: nothing chains into this controller.
  std::vector<hardware_interface::CommandInterface> on_export_reference_interfaces() override {
    return {};
  }

  return_type update_reference_from_subscribers(const rclcpp::Time &,
                                                const rclcpp::Duration &) override {
    return return_type::OK;
  }

  // Real-time: fills the fixed-size input, steps the loop, copies the estimate out.
  return_type update_and_write_commands(const rclcpp::Time &,
                                        const rclcpp::Duration &period) override {
    time_ += period.seconds();
    input_.time = time_;
    input_.n_joints = static_cast<uint32_t>(joints_.size());
    input_.flags = ADM_INPUT_TAU;
    for (size_t i = 0; i < joints_.size(); ++i) {
      input_.q[i] = state_interfaces_[2 * i].get_value();
      input_.tau[i] = state_interfaces_[2 * i + 1].get_value();
    }
    const int32_t status = adm_step(loop_, &input_, &output_);
    if (status < 0) {
      return return_type::ERROR;  // the wrench keeps its last value
    }
    for (int i = 0; i < 6; ++i) wrench_[i] = output_.wrench_tip[i];
    return return_type::OK;
  }

private:
  AdmHandle *loop_ = nullptr;
  AdmInput input_{};
  AdmOutput output_{};
  std::array<double, 6> wrench_{};
  double time_ = 0.0;
  std::vector<std::string> joints_;
  std::string deployment_, sensor_;
};

}  // namespace admittance_ffi_examples

PLUGINLIB_EXPORT_CLASS(admittance_ffi_examples::AdmittanceEstimator,
                       controller_interface::ChainableControllerInterface)
