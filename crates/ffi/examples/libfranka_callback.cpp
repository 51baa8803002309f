// The admittance loop inside a libfranka torque-control callback (docs/ffi.md).
//
// NOT BUILT HERE: it needs a libfranka install (0.9 or later) and a Franka arm (Panda or
// FR3) with the FCI enabled; CI builds only tests/cpp/loop_test.cpp, which exercises the
// same calls against the simulated arm. To build it next to libfranka:
//
//   cargo build --release -p admittance-ffi
//   g++ -std=c++17 -O2 -I crates/ffi/include crates/ffi/examples/libfranka_callback.cpp \
//       target/release/libadmittance_ffi.a -lfranka -lpthread -ldl -lm -o libfranka_callback
//   admittance deploy scenarios/panda_admittance.toml --variant learned --out deploy/panda
//   ./libfranka_callback 172.16.0.2 deploy/panda
//
// The deployment folder (docs/your_robot.md) names the arm (URDF, base, tip), the
// controller, the admittance model and the observer with its trained network, each file
// checked against the folder's manifest; adm_create never trains. Its URDF's joint order
// must be the robot's. Without a desired motion the loop holds the first measured pose.
//
// Three things differ from the simulator and are handled here:
// * Franka's FCI compensates gravity itself: the commanded torque must not contain it. The
//   scenario's controllers command the whole torque (PD with gravity compensation), so the
//   robot's own gravity vector is subtracted before sending.
// * The measured torque for the observer is the link-side joint torque tau_J, the quantity
//   franka_ros2 records as `measured_joint_states` effort (the free-motion data for
//   training should come from the same signal).
// * The callback is called every 1 ms; after a lost packet `period` is 2 ms. The loop's
//   filters assume one control period per call: a longer period is passed on as time.

#include "admittance.h"

#include <franka/exception.h>
#include <franka/model.h>
#include <franka/robot.h>

#include <array>
#include <cstdio>
#include <cstring>

int main(int argc, char **argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s ROBOT_IP DEPLOY_DIR\n", argv[0]);
        return 2;
    }
    // Not real-time: load the deployment folder and allocate the loop.
    AdmConfig config;
    std::memset(&config, 0, sizeof config);
    config.abi_version = ADM_ABI_VERSION;
    config.n_joints = 7;
    config.deployment_path = argv[2];
    AdmHandle *loop = adm_create(&config);
    if (!loop) {
        char msg[1024];
        adm_last_error(nullptr, msg, sizeof msg);
        std::fprintf(stderr, "adm_create: %s\n", msg);
        return 1;
    }

    int exit_code = 0;
    try {
        franka::Robot robot(argv[1]);
        franka::Model model = robot.loadModel();
        // Contact thresholds well above what a person's push gives, so that the admittance
        // model, not the robot's reflex, answers the push.
        robot.setCollisionBehavior({{40, 40, 36, 36, 32, 28, 24}}, {{40, 40, 36, 36, 32, 28, 24}},
                                   {{40, 40, 40, 40, 40, 40}}, {{40, 40, 40, 40, 40, 40}});

        AdmInput in;
        std::memset(&in, 0, sizeof in);
        AdmOutput out;
        double time = 0.0;
        int32_t last_status = ADM_OK;

        // Real-time: adm_step allocates nothing and takes no lock; neither does this body
        // (model.gravity is libfranka's own real-time call).
        auto callback = [&](const franka::RobotState &state,
                            franka::Duration period) -> franka::Torques {
            time += period.toSec();
            in.time = time;
            in.n_joints = 7;
            in.flags = ADM_INPUT_TAU;  // measured link torques; no desired motion: the first pose is held
            for (int i = 0; i < 7; ++i) {
                in.q[i] = state.q[i];
                in.tau[i] = state.tau_J[i];
            }
            last_status = adm_step(loop, &in, &out);
            std::array<double, 7> tau{};
            if (last_status < 0) {
                // An error (wrong joint count, a caught panic): stop with zero torque
                // (the robot holds itself against gravity).
                return franka::MotionFinished(franka::Torques(tau));
            }
            // ADM_FAULT: out.tau_cmd is the controller's safe hold; send it like any other.
            const std::array<double, 7> gravity = model.gravity(state);
            for (int i = 0; i < 7; ++i) tau[i] = out.tau_cmd[i] - gravity[i];
            return tau;
        };
        robot.control(callback, /*limit_rate=*/true);

        if (last_status < 0) {
            char msg[1024];
            adm_last_error(loop, msg, sizeof msg);
            std::fprintf(stderr, "adm_step stopped the motion: %s\n", msg);
            exit_code = 1;
        }
    } catch (const franka::Exception &e) {
        std::fprintf(stderr, "libfranka: %s\n", e.what());
        exit_code = 1;
    }
    adm_destroy(loop);
    return exit_code;
}
