// The CVODE BDF stepper of simulate() (lib/src/simulate/stepper.hpp): Newton iterations, dense
// direct solver. With lib/src/simulate/arkode.cpp the only files that include SUNDIALS
// (docs/architecture.md).

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

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
    if (!std::isfinite(yv[i])) return -1;  // unrecoverable
  }
  return rhs(s, yv, N_VGetArrayPointer(dy)) ? 0 : 1;  // 1: recoverable, CVODE cuts the step
}

int root_callback(realtype, N_Vector y, realtype* g, void* data) {
  roots(*static_cast<System*>(data), N_VGetArrayPointer(y), g);
  return 0;
}

void quiet(int, const char*, const char*, char* msg, void* data) { *static_cast<std::string*>(data) = msg; }

class Bdf final : public Stepper {
 public:
  Bdf(System& system, std::size_t n, double rtol, const std::vector<double>& atol, int n_roots) : n_roots_(n_roots) {
    const auto len = static_cast<sunindextype>(n);
    if (SUNContext_Create(nullptr, &ctx_) != 0) throw std::runtime_error("SUNDIALS: cannot create a context");
    y_ = N_VNew_Serial(len, ctx_);
    atol_ = N_VNew_Serial(len, ctx_);
    for (std::size_t i = 0; i < n; ++i) {
      N_VGetArrayPointer(y_)[i] = 0.0;
      N_VGetArrayPointer(atol_)[i] = atol[i];
    }
    mem_ = CVodeCreate(CV_BDF, ctx_);
    if (mem_ == nullptr) throw std::runtime_error("SUNDIALS: CVodeCreate failed");
    CVodeSetErrHandlerFn(mem_, &quiet, &message_);
    CVodeInit(mem_, &rhs_callback, 0.0, y_);
    CVodeSVtolerances(mem_, rtol, atol_);
    CVodeSetUserData(mem_, &system);
    A_ = SUNDenseMatrix(len, len, ctx_);
    LS_ = SUNLinSol_Dense(y_, A_, ctx_);
    CVodeSetLinearSolver(mem_, LS_, A_);
    if (n_roots_ > 0) {
      CVodeRootInit(mem_, n_roots_, &root_callback);
      CVodeSetNoInactiveRootWarn(mem_);
    }
  }
  ~Bdf() override {
    if (mem_) CVodeFree(&mem_);
    if (LS_) SUNLinSolFree(LS_);
    if (A_) SUNMatDestroy(A_);
    if (atol_) N_VDestroy(atol_);
    if (y_) N_VDestroy(y_);
    if (ctx_) SUNContext_Free(&ctx_);
  }
  Bdf(const Bdf&) = delete;
  Bdf& operator=(const Bdf&) = delete;

  double* y() override { return N_VGetArrayPointer(y_); }
  void restart(double t, double t_stop, const std::vector<int>& directions) override {
    CVodeReInit(mem_, t, y_);
    CVodeSetStopTime(mem_, t_stop);
    if (n_roots_ > 0) {
      std::vector<int> d = directions;
      CVodeSetRootDirection(mem_, d.data());
    }
  }
  StepOutcome step(double t_stop, double& t) override {
    const int flag = CVode(mem_, t_stop, y_, &t, CV_ONE_STEP);
    if (flag == CV_ROOT_RETURN) return StepOutcome::root;
    if (flag == CV_REPTD_RHSFUNC_ERR || flag == CV_RHSFUNC_FAIL || flag == CV_UNREC_RHSFUNC_ERR) {
      return StepOutcome::rhs_failure;
    }
    return flag < 0 ? StepOutcome::failure : StepOutcome::ok;
  }
  void root_info(std::vector<int>& found) override {
    found.assign(static_cast<std::size_t>(n_roots_), 0);
    if (n_roots_ > 0) CVodeGetRootInfo(mem_, found.data());
  }
  bool interpolate(double t, double* out) override {
    N_Vector v = N_VMake_Serial(N_VGetLength(y_), out, ctx_);
    const int flag = CVodeGetDky(mem_, t, 0, v);
    N_VDestroy(v);
    return flag == CV_SUCCESS;
  }
  const std::string& message() const override { return message_; }

 private:
  int n_roots_ = 0;
  SUNContext ctx_ = nullptr;
  N_Vector y_ = nullptr;
  N_Vector atol_ = nullptr;
  SUNMatrix A_ = nullptr;
  SUNLinearSolver LS_ = nullptr;
  void* mem_ = nullptr;
  std::string message_;
};

}  // namespace

std::unique_ptr<Stepper> make_bdf(System& system, std::size_t n, double rtol, const std::vector<double>& atol,
                                  int n_roots) {
  return std::make_unique<Bdf>(system, n, rtol, atol, n_roots);
}

}  // namespace fivebar::dynamics_detail
