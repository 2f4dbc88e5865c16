#include "device/launcher.h"

#include <algorithm>
#include <string>

#include "scene/render_types.h"

namespace opsila {

void Launcher::run(cl::Kernel& k, const char* name, std::size_t global, std::size_t local, int round,
                   const std::vector<cl::Event>* wait, Watch watch) {
  if (local == 0) {
    // A fixed work-group size per kernel, from what the kernel allows: drivers
    // that compile per work-group size (PoCL) then compile each kernel once.
    std::size_t allowed = 0;
    cl_check(k.getWorkGroupInfo(rt_.device().device, CL_KERNEL_WORK_GROUP_SIZE, &allowed),
             "clGetKernelWorkGroupInfo(CL_KERNEL_WORK_GROUP_SIZE)");
    local = rt_.group_size();
    while (local > 1 && local > allowed) local /= 2;
  }
  global = round_up(std::max<std::size_t>(global, 1), local);
  cl::Event ev;
  const bool timed = !sparse_ || watch == Watch::always;
  cl_int err = rt_.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(global), cl::NDRange(local), wait,
                                                timed ? &ev : nullptr);
  cl_check(err, (std::string("clEnqueueNDRangeKernel(") + name + ")").c_str());
  pending_.push_back({name, round, ev});
}

void Launcher::check(cl_int err, const char* what) {
  auto describe = [](const Pending& p) {
    return std::string(p.name) + (p.round >= 0 ? " (round " + std::to_string(p.round) + ")" : std::string());
  };
  for (std::size_t i = checked_; i < pending_.size(); ++i) {
    if (!pending_[i].ev()) continue;  // launched without an event (sparse)
    cl_int status = CL_COMPLETE;
    if (pending_[i].ev.getInfo(CL_EVENT_COMMAND_EXECUTION_STATUS, &status) != CL_SUCCESS) break;
    if (status < 0)
      throw ClError("kernel " + describe(pending_[i]) + " failed on the device: " + cl_error_name(status) + " (" +
                    std::to_string(status) + "), seen at " + what);
    if (status != CL_COMPLETE) break;  // in-order queue: nothing later has finished either
    checked_ = i + 1;
  }
  if (err != CL_SUCCESS)
    throw ClError(std::string(what) + ": " + cl_error_name(err) + " (" + std::to_string(err) + ")" +
                  (pending_.empty() ? std::string() : " after kernel " + describe(pending_.back())));
}

void Launcher::record(const char* name, int round, double seconds, double queued, double started) {
  if (sink_.size() < record_cap_) {
    LaunchRecord r{name, round, seconds};
    r.queued = queued, r.started = started;
    sink_.push_back(std::move(r));
    return;
  }
  // Past the cap: into the kernel's folded record. They all lie past the
  // cap, one per kernel name, so the search stays short.
  auto it = std::find_if(sink_.begin() + std::ptrdiff_t(record_cap_), sink_.end(), [&](const LaunchRecord& r) {
    return r.round == LaunchRecord::kFoldedRound && r.name == name;
  });
  if (it == sink_.end()) {
    sink_.push_back({name, LaunchRecord::kFoldedRound, seconds, 1});
    return;
  }
  it->seconds += seconds;
  it->launches += 1;
}

void Launcher::harvest() {
  check(CL_SUCCESS, "collecting kernel timings");
  // Launches still running (and, in an in-order queue, all after them) stay
  // pending for a later harvest.
  std::size_t done = 0;
  for (; done < pending_.size(); ++done) {
    const Pending& p = pending_[done];
    if (!p.ev()) {  // no event, no time: counted alone
      record(p.name, p.round, 0, -1, -1);
      continue;
    }
    cl_int status = CL_COMPLETE;
    cl_check(p.ev.getInfo(CL_EVENT_COMMAND_EXECUTION_STATUS, &status), "clGetEventInfo(execution status)");
    if (status != CL_COMPLETE) break;
    cl_ulong tq = 0, t0 = 0, t1 = 0;
    if (p.ev.getProfilingInfo(CL_PROFILING_COMMAND_START, &t0) == CL_SUCCESS &&
        p.ev.getProfilingInfo(CL_PROFILING_COMMAND_END, &t1) == CL_SUCCESS) {
      const bool queued = p.ev.getProfilingInfo(CL_PROFILING_COMMAND_QUEUED, &tq) == CL_SUCCESS && tq <= t0;
      if (queued && !based_) base_ns_ = tq, based_ = true;
      auto since = [this](cl_ulong t) { return t >= base_ns_ ? (t - base_ns_) * 1e-9 : -((base_ns_ - t) * 1e-9); };
      record(p.name, p.round, (t1 - t0) * 1e-9, queued && based_ ? since(tq) : -1, based_ ? since(t0) : -1);
    }
  }
  std::vector<Pending> running(pending_.begin() + done, pending_.end());
  pending_ = std::move(running);
  checked_ = 0;
}

double compile_waits(const std::vector<LaunchRecord>& launches) {
  double waits = 0, previous_end = 0;
  for (const LaunchRecord& r : launches) {
    if (r.queued < 0 || r.started < 0) continue;  // folded, or no profiling times
    const double wait = r.started - std::max(r.queued, previous_end);
    if (wait > 0.005) waits += wait;
    previous_end = std::max(previous_end, r.started + r.seconds);
  }
  return waits;
}

}  // namespace opsila
