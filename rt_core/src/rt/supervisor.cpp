#include "hapfluid/rt/supervisor.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>

#include "hapfluid/config/log.hpp"
#include "hapfluid/rt/trace_csv.hpp"
#include "hapfluid/safety/flags.hpp"

namespace hapfluid::rt {

Supervisor::Supervisor(RtLoop& loop, SupervisorOptions options) : loop_(loop), options_(std::move(options)) {
  if (!options_.trace_path.empty()) {
    trace_file_ = std::fopen(options_.trace_path.c_str(), "w");
    if (!trace_file_) throw std::runtime_error("--trace " + options_.trace_path + ": cannot create the file");
    write_trace_header(trace_file_, static_cast<unsigned>(loop_.device_count()));
    if (loop_.trace_ring().valid()) trace_reader_ = shm::RingReader(loop_.trace_ring().segment(), 0);
  }
}

Supervisor::~Supervisor() {
  stop();
  if (trace_file_) std::fclose(trace_file_);
}

void Supervisor::start() {
  running_.store(true);
  thread_ = std::thread([this] {
    // Explicitly ordinary scheduling, even if created after the RT set-up.
    sched_param param{};
    pthread_setschedparam(pthread_self(), SCHED_OTHER, &param);
    // Keep off the loop's CPU when it has one (and another CPU exists).
    int rt_cpu = loop_.rig().rt.cpu;
    if (rt_cpu >= 0 && sysconf(_SC_NPROCESSORS_ONLN) > 1) {
      cpu_set_t set;
      CPU_ZERO(&set);
      for (long cpu = 0; cpu < sysconf(_SC_NPROCESSORS_ONLN) && cpu < CPU_SETSIZE; ++cpu)
        if (cpu != rt_cpu) CPU_SET(cpu, &set);
      pthread_setaffinity_np(pthread_self(), sizeof set, &set);
    }
    run();
  });
}

void Supervisor::stop() {
  if (!running_.exchange(false)) return;
  if (thread_.joinable()) thread_.join();
  step(/*final=*/true);
  if (trace_file_)
    log::info("trace: %llu records written to %s, %llu lost (drainer too slow)",
              (unsigned long long)(trace_reader_.position() - trace_reader_.lost()), options_.trace_path.c_str(),
              (unsigned long long)trace_reader_.lost());
  if (notifier_.active()) notifier_.send("STOPPING=1");
}

void Supervisor::run() {
  while (running_.load()) {
    step(false);
    std::this_thread::sleep_for(std::chrono::milliseconds(options_.poll_ms));
  }
}

void Supervisor::step(bool final) {
  std::uint64_t now = shm::monotonic_ns();
  if (!final) manage_sim();

  std::uint64_t ticks = loop_.ticks();
  if (notifier_.active()) {
    if (!ready_sent_ && ticks > 0) {
      ready_sent_ = notifier_.send("READY=1\nSTATUS=1 kHz loop running");
      last_ping_ns_ = now;
      last_ping_tick_ = ticks;
    }
    // Watchdog pings only while the loop makes progress: a hung loop gets restarted by systemd.
    std::uint64_t interval = notifier_.watchdog_ping_interval_ns();
    if (ready_sent_ && interval && now - last_ping_ns_ >= interval && ticks > last_ping_tick_) {
      notifier_.send("WATCHDOG=1");
      last_ping_ns_ = now;
      last_ping_tick_ = ticks;
    }
  }

  if (!pending_fault_tick_) {
    if (std::uint64_t fault_tick = loop_.take_fault_tick()) {
      pending_fault_tick_ = fault_tick;
      pending_fault_bits_ = loop_.last_fault_bits();
    }
  }
  // Dump once a few post-fault ticks exist (or now, at shutdown).
  if (pending_fault_tick_ && (final || ticks >= pending_fault_tick_ + 20)) {
    // At most one dump per second: a flapping link must not fill the disk.
    if (final || now - last_dump_ns_ > 1'000'000'000ull || dumps_ == 0)
      dump_flight_recorder(pending_fault_tick_, pending_fault_bits_);
    pending_fault_tick_ = 0;
  }
  drain_trace();
}

void Supervisor::manage_sim() {
  std::uint64_t now = shm::monotonic_ns();
  // Free a mapping the loop no longer uses.
  if (sim_retired_ && sim_current_ && loop_.sim_epoch_in_use() == sim_current_->epoch) sim_retired_.reset();
  if (now < next_sim_check_ns_ || sim_retired_) return;
  next_sim_check_ns_ = now + 50'000'000ull;  // 20 Hz

  if (sim_current_) {
    shm::WriterStatus status = sim_current_->reader.check_liveness(now, 0);
    if (status == shm::WriterStatus::live) return;
    std::string message = std::string("sim_samples: ") + shm::to_string(status);
    if (message != last_sim_message_) {
      log::warning("%s%s", message.c_str(),
                   status == shm::WriterStatus::replaced ? ": attaching to the new segment"
                   : "; the wrench ramps down while no fresh samples arrive");
      last_sim_message_ = message;
    }
    if (status != shm::WriterStatus::replaced) {
      // A dead/closed/corrupt writer whose name is gone or unchanged: wait for a new segment.
      if (status != shm::WriterStatus::dead && status != shm::WriterStatus::closed &&
          status != shm::WriterStatus::corrupt)
        return;
    }
  }
  try {
    auto attachment = std::make_unique<SimAttachment>();
    attachment->reader = shm::LatestReader::attach(options_.sim_segment, shm::ChannelKind::sim_samples,
                                                   sizeof(shm::SimSample));
    if (sim_current_ && attachment->reader.segment().inode() == sim_current_->reader.segment().inode()) return;
    attachment->epoch = ++sim_epoch_;
    // The segment's own name: a fallback when another user holds the channel's name.
    log::info("sim_samples: attached %s (writer pid %d)",
              attachment->reader.segment().name().c_str(), attachment->reader.segment().layout().writer_pid);
    last_sim_message_.clear();
    last_attach_error_.clear();
    loop_.offer_sim(attachment.get());
    sim_retired_ = std::move(sim_current_);
    sim_current_ = std::move(attachment);
  } catch (const shm::ShmError& e) {
    // Said once per cause: a corrupt segment left in /dev/shm fails every check (20 Hz).
    if (last_attach_error_ != e.what()) {
      log::warning("%s", e.what());
      last_attach_error_ = e.what();
    }
  }
}

void Supervisor::dump_flight_recorder(std::uint64_t fault_tick, std::uint32_t fault_bits) {
  std::error_code ec;
  std::filesystem::create_directories(options_.flight_dir, ec);
  std::string names = safety::fault_names(fault_bits);
  for (char& c : names)
    if (c == '|') c = '+';
  std::string path = options_.flight_dir + "/flight-tick" + std::to_string(fault_tick) + "-" + names + ".csv";
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (!out) {
    log::error("flight recorder: cannot write %s", path.c_str());
    return;
  }
  unsigned devices = static_cast<unsigned>(loop_.device_count());
  write_trace_header(out, devices);
  shm::RingReader reader(loop_.flight_recorder().segment(), 0);
  std::uint64_t window = loop_.flight_recorder_ticks();
  std::uint64_t first = fault_tick > window ? fault_tick - window : 1;
  std::uint64_t last = loop_.ticks();
  std::uint64_t rows = 0;
  shm::TraceRecord record{};
  for (std::uint64_t tick = first; tick <= last; ++tick)  // record index = tick - 1
    if (reader.read_at(tick - 1, &record, sizeof record)) {
      write_trace_row(out, record, devices);
      ++rows;
    }
  std::fclose(out);
  ++dumps_;
  last_dump_ns_ = shm::monotonic_ns();
  log::error("FAULT %s at tick %llu: flight recorder (%llu ticks) dumped to %s", names.c_str(),
             (unsigned long long)fault_tick, (unsigned long long)rows, path.c_str());
}

void Supervisor::drain_trace() {
  if (!trace_file_) return;
  unsigned devices = static_cast<unsigned>(loop_.device_count());
  shm::TraceRecord record{};
  while (trace_reader_.next(record)) write_trace_row(trace_file_, record, devices);
  std::fflush(trace_file_);
}

}  // namespace hapfluid::rt
