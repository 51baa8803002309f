// The smallest robot loop on the C ABI (docs/your_robot.md, docs/ffi.md): load a deployment
// folder written by `admittance deploy`, then step it once per control period with the
// robot's measured angles and torques. Here a stand-in for Baxter's left arm (7 joints)
// rests at a pose and measures the command as its joint torque (the drives apply it, the
// arm holds still): the loop holds that pose, and nobody touches it, so the estimated
// external torque is the observer's model error alone (about 4.5 N m with the momentum
// variant of scenarios/admittance.toml, whose nominal model has 80 % of the inertias; an
// identified model makes it smaller). On a robot, q and tau come from its sensors and
// tau_cmd goes to its drives.
//
// Build and run (from the repository's root; one command per line):
//   cargo build --release -p admittance-ffi
//   g++ -std=c++17 -O2 -I crates/ffi/include crates/ffi/examples/robot_loop.cpp
//       target/release/libadmittance_ffi.a -lpthread -ldl -lm -o robot_loop
//   admittance deploy scenarios/admittance.toml --variant momentum --out deploy_baxter
//   ./robot_loop deploy_baxter
#include "admittance.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

int main(int argc, char **argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: robot_loop DEPLOY_DIR\n");
        return 2;
    }
    AdmConfig config;
    std::memset(&config, 0, sizeof config);
    config.abi_version = ADM_ABI_VERSION;
    config.n_joints = 7;
    config.deployment_path = argv[1];
    AdmHandle *h = adm_create(&config);  // reads and checks the folder: before the loop
    if (!h) {
        char msg[1024];
        adm_last_error(nullptr, msg, sizeof msg);
        std::fprintf(stderr, "robot_loop: %s\n", msg);
        return 1;
    }
    const uint32_t n = adm_n_joints(h);
    const double dt = adm_control_period(h);
    const double pose[7] = {0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5};
    AdmInput in;
    std::memset(&in, 0, sizeof in);
    AdmOutput out;
    int faults = 0;
    for (int k = 0; k < 3000; ++k) {  // the robot's control loop: real-time from here
        in.time = k * dt;
        in.n_joints = n;
        in.flags = ADM_INPUT_TAU;  // measured torques; no ADM_INPUT_DESIRED: hold the pose
        for (uint32_t i = 0; i < n; ++i) {
            in.q[i] = pose[i];                                 // the encoders
            in.tau[i] = out.step > 0 ? out.tau_cmd[i] : 0.0;  // the drives apply the command
        }
        const int32_t status = adm_step(h, &in, &out);
        if (status < 0) {
            char msg[1024];
            adm_last_error(h, msg, sizeof msg);
            std::fprintf(stderr, "robot_loop: step %d: %s\n", k, msg);
            break;
        }
        faults += status == ADM_FAULT;
        // send out.tau_cmd[0..n] to the drives here
    }
    double largest = 0.0;
    for (uint32_t i = 0; i < n; ++i)
        largest = std::max(largest, std::abs(out.tau_ext[i]));
    std::printf("robot_loop: %u joints at %.0f Hz, %llu steps, %d with a fault; largest "
                "estimated external torque %.3f N m; reference on joint 1 %.4f rad (pose "
                "%.4f); flags 0x%x\n",
                n, 1.0 / dt, (unsigned long long)out.step, faults, largest, out.q_r[1], pose[1],
                out.flags);
    adm_destroy(h);
    return 0;
}
