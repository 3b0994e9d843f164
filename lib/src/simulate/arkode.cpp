// The explicit Runge-Kutta stepper of simulate() (lib/src/simulate/stepper.hpp): ARKODE ERKStep
// with the Dormand-Prince 5(4) table (Dormand & Prince, J. Comput. Appl. Math. 6(1), 1980), the
// comparison to CVODE's BDF on the stiff motor. With lib/src/simulate/cvode.cpp the only files
// that include SUNDIALS (docs/architecture.md).

#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <cmath>
#include <stdexcept>

#include "simulate/stepper.hpp"

namespace fivebar::dynamics_detail {

namespace {

int rhs_callback(realtype, N_Vector y, N_Vector dy, void* data) {
  System& s = *static_cast<System*>(data);
  ++s.evaluations;
  const double* yv = N_VGetArrayPointer(y);
  for (sunindextype i = 0; i < N_VGetLength(y); ++i) {
    if (!std::isfinite(yv[i])) return -1;
  }
  return rhs(s, yv, N_VGetArrayPointer(dy)) ? 0 : 1;  // 1: recoverable, ERKStep retries a smaller step
}

int root_callback(realtype, N_Vector y, realtype* g, void* data) {
  roots(*static_cast<System*>(data), N_VGetArrayPointer(y), g);
  return 0;
}

void quiet(int, const char*, const char*, char* msg, void* data) { *static_cast<std::string*>(data) = msg; }

class Erk final : public Stepper {
 public:
  Erk(System& system, std::size_t n, double rtol, const std::vector<double>& atol, int n_roots) : n_roots_(n_roots) {
    const auto len = static_cast<sunindextype>(n);
    if (SUNContext_Create(nullptr, &ctx_) != 0) throw std::runtime_error("SUNDIALS: cannot create a context");
    y_ = N_VNew_Serial(len, ctx_);
    atol_ = N_VNew_Serial(len, ctx_);
    for (std::size_t i = 0; i < n; ++i) {
      N_VGetArrayPointer(y_)[i] = 0.0;
      N_VGetArrayPointer(atol_)[i] = atol[i];
    }
    mem_ = ERKStepCreate(&rhs_callback, 0.0, y_, ctx_);
    if (mem_ == nullptr) throw std::runtime_error("SUNDIALS: ERKStepCreate failed");
    ERKStepSetErrHandlerFn(mem_, &quiet, &message_);
    ERKStepSetTableNum(mem_, ARKODE_DORMAND_PRINCE_7_4_5);
    ERKStepSVtolerances(mem_, rtol, atol_);
    ERKStepSetUserData(mem_, &system);
    if (n_roots_ > 0) {
      ERKStepRootInit(mem_, n_roots_, &root_callback);
      ERKStepSetNoInactiveRootWarn(mem_);
    }
  }
  ~Erk() override {
    if (mem_) ERKStepFree(&mem_);
    if (atol_) N_VDestroy(atol_);
    if (y_) N_VDestroy(y_);
    if (ctx_) SUNContext_Free(&ctx_);
  }
  Erk(const Erk&) = delete;
  Erk& operator=(const Erk&) = delete;

  double* y() override { return N_VGetArrayPointer(y_); }
  void restart(double t, double t_stop, const std::vector<int>& directions) override {
    ERKStepReInit(mem_, &rhs_callback, t, y_);
    ERKStepSetStopTime(mem_, t_stop);
    if (n_roots_ > 0) {
      std::vector<int> d = directions;
      ERKStepSetRootDirection(mem_, d.data());
    }
  }
  StepOutcome step(double t_stop, double& t) override {
    const int flag = ERKStepEvolve(mem_, t_stop, y_, &t, ARK_ONE_STEP);
    if (flag == ARK_ROOT_RETURN) return StepOutcome::root;
    if (flag == ARK_REPTD_RHSFUNC_ERR || flag == ARK_RHSFUNC_FAIL || flag == ARK_UNREC_RHSFUNC_ERR ||
        flag == ARK_FIRST_RHSFUNC_ERR) {
      return StepOutcome::rhs_failure;
    }
    return flag < 0 ? StepOutcome::failure : StepOutcome::ok;
  }
  void root_info(std::vector<int>& found) override {
    found.assign(static_cast<std::size_t>(n_roots_), 0);
    if (n_roots_ > 0) ERKStepGetRootInfo(mem_, found.data());
  }
  bool interpolate(double t, double* out) override {
    N_Vector v = N_VMake_Serial(N_VGetLength(y_), out, ctx_);
    const int flag = ERKStepGetDky(mem_, t, 0, v);
    N_VDestroy(v);
    return flag == ARK_SUCCESS;
  }
  const std::string& message() const override { return message_; }

 private:
  int n_roots_ = 0;
  SUNContext ctx_ = nullptr;
  N_Vector y_ = nullptr;
  N_Vector atol_ = nullptr;
  void* mem_ = nullptr;
  std::string message_;
};

}  // namespace

std::unique_ptr<Stepper> make_erk(System& system, std::size_t n, double rtol, const std::vector<double>& atol,
                                  int n_roots) {
  return std::make_unique<Erk>(system, n, rtol, atol, n_roots);
}

}  // namespace fivebar::dynamics_detail
