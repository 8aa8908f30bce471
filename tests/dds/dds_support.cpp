#include "dds_support.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "arbiter/trace_reader.hpp"
#include "dds.hpp"
#include "probe.hpp"
#include "test_support.hpp"

extern char** environ;

namespace arbiter::dds_test {

DomainLease::DomainLease() {
  constexpr int kFirst = 100;
  constexpr int kCount = 130;
  const std::string dir = std::filesystem::temp_directory_path().string();
  const int start = static_cast<int>(getpid()) % kCount;
  for (int i = 0; i < kCount; ++i) {
    const int id = kFirst + (start + i) % kCount;
    const std::string path = dir + "/arbiter-dds-test-domain-" + std::to_string(id) + ".lock";
    // Not close-on-exec: the children started under the lease inherit the lock, which so lasts
    // until the last of them is gone, even if the test process is not.
    const int fd = open(path.c_str(), O_CREAT | O_RDWR, 0666);
    if (fd < 0) continue;
    if (flock(fd, LOCK_EX | LOCK_NB) == 0) {
      id_ = id;
      fd_ = fd;
      return;
    }
    close(fd);
  }
  throw std::runtime_error("no free DDS domain id for the test");
}

DomainLease::~DomainLease() {
  if (fd_ >= 0) close(fd_);
}

std::string loopback_xml() {
  return ARBITER_SOURCE_DIR "/configs/soccer/split/cyclonedds-loopback.xml";
}

std::string fill(std::string text, const Values& values) {
  for (const auto& [key, value] : values) {
    const std::string marker = "{" + key + "}";
    for (auto at = text.find(marker); at != std::string::npos; at = text.find(marker, at)) {
      text.replace(at, marker.size(), value);
      at += value.size();
    }
  }
  return text;
}

Child::Child(const std::vector<std::string>& argv, const std::string& output,
             const std::string& directory)
    : output_(output) {
  std::vector<char*> args;
  for (const auto& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  std::vector<std::string> variables;
  for (char** variable = environ; *variable != nullptr; ++variable) {
    variables.emplace_back(*variable);
  }
#if defined(__SANITIZE_ADDRESS__)
  // GCC 12's LeakSanitizer can crash at exit ("Tracer caught signal 11") walking the dynamic TLS
  // of Cyclone DDS in a process that dlopen()ed the dds plugin, as `arbiter run` does. Leaks of
  // the bridge are checked in the test processes, which link it; the children skip the check.
  bool set = false;
  for (auto& variable : variables) {
    if (variable.rfind("ASAN_OPTIONS=", 0) == 0) {
      variable += ":detect_leaks=0";
      set = true;
    }
  }
  if (!set) variables.emplace_back("ASAN_OPTIONS=detect_leaks=0");
#endif
  std::vector<char*> envp;
  for (auto& variable : variables) envp.push_back(variable.data());
  envp.push_back(nullptr);
  // fork and exec rather than posix_spawn, for PR_SET_PDEATHSIG: a test process that aborts runs
  // no destructor, and a child left running would disturb later tests on its DDS domain. Between
  // fork and exec the child calls only async-signal-safe functions.
  const pid_t parent = getpid();
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("cannot start " + argv[0]);
  if (pid_ == 0) {
    if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent) _exit(127);
    if (!directory.empty() && chdir(directory.c_str()) != 0) _exit(127);
    const int fd = open(output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0 || dup2(fd, 1) < 0 || dup2(fd, 2) < 0) _exit(127);
    close(fd);
    execve(args[0], args.data(), envp.data());
    _exit(127);
  }
}

Child::~Child() {
  if (status_) return;
  ::kill(pid_, SIGKILL);
  int status = 0;
  waitpid(pid_, &status, 0);
}

void Child::signal(int signal) {
  if (!status_) ::kill(pid_, signal);
}

std::optional<int> Child::wait(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!status_) {
    int status = 0;
    const pid_t done = waitpid(pid_, &status, WNOHANG);
    if (done == pid_) {
      status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      break;
    }
    if (std::chrono::steady_clock::now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return status_;
}

std::optional<int> Child::stop(int signal, std::chrono::milliseconds timeout) {
  this->signal(signal);
  return wait(timeout);
}

std::string Child::output() const {
  std::ifstream in(output_);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool Child::wait_for_output(const std::string& text, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (output().find(text) != std::string::npos) return true;
    if (wait(std::chrono::milliseconds(20))) return output().find(text) != std::string::npos;
  }
  return false;
}

std::vector<std::string> arbiter_run(const std::string& config, std::uint64_t steps,
                                     const std::string& trace, bool quiet) {
  std::vector<std::string> argv = {
      ARBITER_CLI,  "--plugin-path", ARBITER_DDS_TEST_PLUGIN_DIR, "run", config,
      "--realtime", "--steps",       std::to_string(steps)};
  if (!trace.empty()) {
    argv.push_back("--trace");
    argv.push_back(trace);
  }
  if (quiet) argv.push_back("--quiet");
  return argv;
}

std::vector<nlohmann::json> read_trace(const std::string& path) {
  const auto source = open_trace(path);
  std::vector<nlohmann::json> records;
  TraceRecord record;
  while (source->next(record)) {
    if (record.kind == TraceRecord::Kind::kStep || record.kind == TraceRecord::Kind::kSafe) {
      records.push_back(nlohmann::json::parse(record.text));
    }
  }
  if (source->error()) throw std::runtime_error(format(*source->error()));
  return records;
}

Registry make_registry() {
  Registry registry = test::make_test_registry();
  registry.set_origin("dds");
  dds::register_classes(registry);
  registry.set_origin("probe");
  register_probe(registry);
  return registry;
}

Program load_file(const std::string& path, Registry& registry) {
  return load_program(path, registry);
}

Values Setup::values() const {
  return {{"domain", std::to_string(domain.id())}, {"xml", loopback_xml()}};
}

std::string Setup::write(const std::string& name, const std::string& text, const Values& more) {
  return dir.write(name, fill(fill(text, more), values()));
}

Program Setup::load(const std::string& name, const std::string& text, const Values& more) {
  return load_file(write(name, text, more), registry);
}

std::string Setup::side(const std::string& layers, const std::string& self,
                        const std::string& other, int rate, bool cli) {
  return write(self + ".yaml",
               "arbiter: 1\nname: {self}\nrate_hz: {rate}\n{plugins}\nlayers:\n" + layers,
               {{"link", kSideLink},
                {"self", self},
                {"other", other},
                {"rate", std::to_string(rate)},
                {"plugins", cli ? "plugins: [dds, dds_probe]" : ""}});
}

const char* const kSideLink = R"(  - name: link
    interface: dds.Bridge
    params:
      domain_id: {domain}
      cyclone_config: {xml}
      namespace: {self}
      topics:
        {other}_flag: /{other}/flag
        {other}_count: /{other}/count
        {other}_level: /{other}/level
        {other}_point: /{other}/point
        {other}_vector: /{other}/vector
        {other}_text: /{other}/text
    actuators:
      {other}_flag: bool
      {other}_count: int
      {other}_level: double
      {other}_point: vec2
      {other}_vector: vec3
      {other}_text: string
    sensors: [flag, count, level, point, vector, text])";

dds::Bridge& bridge_of(const Manager& manager, const std::string& layer) {
  for (const auto& compiled : manager.program().layers) {
    if (compiled.name == layer) return dynamic_cast<dds::Bridge&>(*compiled.interface);
  }
  throw std::runtime_error("no layer " + layer);
}

bool step_until(Manager& manager, const std::function<bool()>& done,
                std::chrono::milliseconds timeout) {
  using Clock = std::chrono::steady_clock;
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / manager.program().rate_hz));
  const auto deadline = Clock::now() + timeout;
  auto next = Clock::now();
  while (Clock::now() < deadline) {
    manager.step();
    if (done()) return true;
    next += period;
    std::this_thread::sleep_until(next);
  }
  return false;
}

nlohmann::json value_of(const Manager& manager, const std::string& actuator) {
  const auto index = manager.program().find_actuator(actuator);
  if (!index) throw std::runtime_error("no actuator " + actuator);
  std::string text;
  manager.program().actuators[*index].type->append_json(manager.actuator_value(*index), text);
  return nlohmann::json::parse(text);
}

bool written(const Manager& manager, const std::string& actuator) {
  const auto index = manager.program().find_actuator(actuator);
  if (!index) throw std::runtime_error("no actuator " + actuator);
  return manager.actuator_written(*index);
}

}  // namespace arbiter::dds_test
