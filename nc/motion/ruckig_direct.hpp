// ruckig's C++ called directly for the planner's 1-DoF solves (issue 17, decision bench B162): the same calculation
// as the Python module's `Ruckig(1).calculate(input, trajectory)` (validate, then the state-to-state calculator, the
// errors thrown) and the read-back of nc/motion/profile.py's `_phases`, without pybind writing the input's fields and
// copying the Trajectory's profiles out (≈ 24k instructions a solve, session 28). Never given intermediate positions:
// only the state-to-state calculator is compiled in (the community build sends waypoints to a web service).
#pragma once

#include <ruckig/calculator_target.hpp>
#include <ruckig/input_parameter.hpp>
#include <ruckig/trajectory.hpp>

namespace deltahil {

class OneDof {
    ruckig::InputParameter<0> inp {1};
    ruckig::TargetCalculator<0> calc {1};
    ruckig::Trajectory<0> traj {1};

    // 0: solved (Working or Finished), 1: another result, 2: thrown (the pybind path's RuckigError)
    int calculate() {
        try {
            // ruckig::Ruckig<0, StandardVector, true>::calculate: validate_input<true>(input, false, true) (no
            // waypoints; delta_time −1 with continuous durations passes), then the calculator with delta_time −1
            if (!inp.template validate<true>(false, true)) {
                return 1;
            }
            bool interrupted {false};
            const ruckig::Result r = calc.template calculate<true>(inp, traj, -1.0, interrupted);
            return (r == ruckig::Result::Working || r == ruckig::Result::Finished) ? 0 : 1;
        } catch (...) {
            return 2;
        }
    }

    // profile.py's _gather: the phases that last, each starting at the time summed so far
    // (the profile's t and j hold 7 phases, its p, v and a 8 states: the first 7 are the phases' starts)
    template<size_t N, size_t M>
    double gather(double t, const std::array<double, N>& pt, const std::array<double, M>& pp,
                  const std::array<double, M>& pv, const std::array<double, M>& pa, const std::array<double, N>& pj) {
        for (size_t k = 0; k < N; ++k) {
            const double x = pt[k];
            if (x > 0.0) {
                t0[n] = t; p[n] = pp[k]; v[n] = pv[k]; a[n] = pa[k]; j[n] = pj[k];
                ++n;
                t += x;
            }
        }
        return t;
    }

public:
    // The last solve's phases (brake pre-phases, the main phases that last, the final state): profile.py's rows
    int n {0};
    double t0[10], p[10], v[10], a[10], j[10];
    double duration {0.0}, p_max {0.0};

    // profile.py's _one_dof + _calculate (with its two retries) + _phases; true where solved
    bool solve(bool velocity, double p0, double v0, double a0, double p1, double v1, double v_max, double a_max,
               double j_max) {
        inp.control_interface = velocity ? ruckig::ControlInterface::Velocity : ruckig::ControlInterface::Position;
        inp.synchronization = ruckig::Synchronization::Time;
        inp.current_position[0] = p0;
        inp.current_velocity[0] = v0;
        inp.current_acceleration[0] = a0;
        inp.target_position[0] = p1;
        inp.target_velocity[0] = v1;
        inp.target_acceleration[0] = 0.0;
        inp.max_velocity[0] = v_max;
        inp.max_acceleration[0] = a_max;
        inp.max_jerk[0] = j_max;
        int s = calculate();
        if (s == 2) {  // _calculate's retries: the acceleration 1e-12 nearer zero, then the jerk 1 ppb lower as well
            inp.current_acceleration[0] = a0 * (1.0 - 1e-12);
            s = calculate();
            if (s == 2) {
                inp.max_jerk[0] = j_max * (1.0 - 1e-9);
                s = calculate();
            }
        }
        if (s != 0) {
            return false;
        }
        const auto profiles = traj.get_profiles();  // a copy: Trajectory keeps its profiles private
        const ruckig::Profile& pr = profiles[0][0];
        n = 0;
        double t = 0.0;
        if (pr.brake.duration > 0.0) {
            t = gather(t, pr.brake.t, pr.brake.p, pr.brake.v, pr.brake.a, pr.brake.j);
        }
        t = gather(t, pr.t, pr.p, pr.v, pr.a, pr.j);
        double pe, ve, ae;
        if (n > 0) {  // the final state, integrated from the last phase as _phases does
            const double h = t - t0[n - 1];
            const double pl = p[n - 1], vl = v[n - 1], al = a[n - 1], jl = j[n - 1];
            pe = pl + h * (vl + h * (al / 2.0 + h * jl / 6.0));
            ve = vl + h * (al + h * jl / 2.0);
            ae = al + h * jl;
        } else {
            pe = pr.p[0]; ve = pr.v[0]; ae = pr.a[0];
        }
        t0[n] = t; p[n] = pe; v[n] = ve; a[n] = ae; j[n] = 0.0;
        ++n;
        duration = traj.get_duration();
        std::vector<ruckig::Bound> extrema(1);
        traj.get_position_extrema(extrema);
        p_max = extrema[0].max;
        return true;
    }
};

}  // namespace deltahil
