// autobio's only C++: one extern "C" function that plans a joint-space path with OMPL 1.5's
// RRTConnect. Validity comes from a callback (the caller's collision check); sampling is seeded
// per call, nearest neighbours are found by linear search (the default GNAT picks pivots with
// OMPL's process-wide generator) and the planner stops after a budget of validity checks, so the
// same inputs give the same path (no wall-clock limit). No simplification here: the caller
// shortcuts with its own seeded RNG. Every C++ exception stays in this file.
#include <ompl/base/StateSampler.h>
#include <ompl/datastructures/NearestNeighborsLinear.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>

#include <cstdint>
#include <memory>

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace {

// Uniform sampling from a generator seeded by the caller, not from OMPL's process-wide seed.
class SeededSampler : public ob::RealVectorStateSampler {
public:
    SeededSampler(const ob::StateSpace *space, std::uint_fast32_t seed) : ob::RealVectorStateSampler(space) {
        rng_.setLocalSeed(seed);
    }
};

}  // namespace

extern "C" {

typedef bool (*autobio_valid_fn)(void *user, const double *q, unsigned dim);

// Returns the number of states written to `out` (dim doubles each, start and goal included),
// 0 when no path was found within `max_checks` validity checks, -1 when the start is invalid,
// -2 when the goal is invalid, -3 when `max_states` is too small, -4 on an OMPL exception and
// -5 on any other planner status (the caller checked bounds, so none is expected).
int autobio_rrt_connect(unsigned dim, const double *lo, const double *hi, const double *start,
                        const double *goal, double range, double resolution,
                        unsigned long long max_checks, unsigned long long seed,
                        autobio_valid_fn valid, void *user, double *out, unsigned max_states) {
    try {
        ompl::msg::setLogLevel(ompl::msg::LOG_NONE);
        auto space = std::make_shared<ob::RealVectorStateSpace>(dim);
        ob::RealVectorBounds bounds(dim);
        for (unsigned i = 0; i < dim; ++i) {
            bounds.setLow(i, lo[i]);
            bounds.setHigh(i, hi[i]);
        }
        space->setBounds(bounds);
        const auto local_seed = static_cast<std::uint_fast32_t>(seed);
        space->setStateSamplerAllocator(
            [local_seed](const ob::StateSpace *s) { return std::make_shared<SeededSampler>(s, local_seed); });

        og::SimpleSetup setup(space);
        unsigned long long checks = 0;
        setup.setStateValidityChecker([&](const ob::State *s) {
            ++checks;
            const auto *v = s->as<ob::RealVectorStateSpace::StateType>();
            return valid(user, v->values, dim);
        });
        setup.getSpaceInformation()->setStateValidityCheckingResolution(resolution);

        ob::ScopedState<> from(space), to(space);
        for (unsigned i = 0; i < dim; ++i) {
            from[i] = start[i];
            to[i] = goal[i];
        }
        if (!valid(user, start, dim)) return -1;
        if (!valid(user, goal, dim)) return -2;
        setup.setStartAndGoalStates(from, to);
        auto planner = std::make_shared<og::RRTConnect>(setup.getSpaceInformation());
        planner->setNearestNeighbors<ompl::NearestNeighborsLinear>();
        if (range > 0) planner->setRange(range);
        setup.setPlanner(planner);
        setup.setup();
        ob::PlannerTerminationCondition budget([&] { return checks >= max_checks; });
        const ob::PlannerStatus status = setup.solve(budget);
        if (status == ob::PlannerStatus::TIMEOUT || status == ob::PlannerStatus::APPROXIMATE_SOLUTION) return 0;
        if (status == ob::PlannerStatus::INVALID_START) return -1;
        if (status == ob::PlannerStatus::INVALID_GOAL) return -2;
        if (status != ob::PlannerStatus::EXACT_SOLUTION) return -5;

        auto &path = setup.getSolutionPath();
        const auto n = path.getStateCount();
        if (n > max_states) return -3;
        for (std::size_t k = 0; k < n; ++k) {
            const auto *v = path.getState(k)->as<ob::RealVectorStateSpace::StateType>();
            for (unsigned i = 0; i < dim; ++i) out[k * dim + i] = v->values[i];
        }
        return static_cast<int>(n);
    } catch (...) {
        return -4;
    }
}

}  // extern "C"
