#pragma once
// Child processes for the stop and kill tests: started in a process group of their own (so that
// mpirun and its ranks can be killed together), output to a file, waited for with a deadline.
#include <fcntl.h>
#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace paloverde::test {

class ChildProcess {
public:
    ChildProcess(const std::vector<std::string>& argv, const std::filesystem::path& log) : log_(log) {
        // Everything the child needs is prepared before the fork: between fork and exec only
        // async-signal-safe calls (the test runner has threads).
        std::vector<char*> args;
        for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
        args.push_back(nullptr);
        const std::string log_path = log.string();
        pid_ = ::fork();
        if (pid_ < 0) throw std::runtime_error("fork failed");
        if (pid_ == 0) {
            ::setpgid(0, 0);
            const int out = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            if (out >= 0) {
                ::dup2(out, 1);
                ::dup2(out, 2);
            }
            ::execvp(args[0], args.data());
            ::_exit(127);
        }
        ::setpgid(pid_, pid_);  // also here: no race with a kill right after the fork
    }
    ~ChildProcess() {
        if (!done_) {
            ::kill(-pid_, SIGKILL);
            ::waitpid(pid_, &status_, 0);
        }
    }
    ChildProcess(const ChildProcess&) = delete;
    ChildProcess& operator=(const ChildProcess&) = delete;

    // Signals the whole process group.
    void signal_group(int number) const { ::kill(-pid_, number); }
    void signal(int number) const { ::kill(pid_, number); }
    pid_t pid() const { return pid_; }

    // Whether it has ended (reaped), without waiting.
    bool finished() {
        if (done_) return true;
        if (::waitpid(pid_, &status_, WNOHANG) == pid_) done_ = true;
        return done_;
    }
    // Waits up to `seconds`; false if it is still running.
    bool wait(double seconds) {
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
        while (!finished()) {
            if (std::chrono::steady_clock::now() > deadline) return false;
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
        return true;
    }
    // After wait(): the exit code, or -1 if a signal ended it.
    int exit_code() const { return done_ && WIFEXITED(status_) ? WEXITSTATUS(status_) : -1; }
    int killed_by() const { return done_ && WIFSIGNALED(status_) ? WTERMSIG(status_) : 0; }
    std::string output() const {
        std::ifstream in(log_);
        std::stringstream s;
        s << in.rdbuf();
        return s.str();
    }

private:
    std::filesystem::path log_;
    pid_t pid_ = -1;
    int status_ = 0;
    bool done_ = false;
};

// Waits up to `seconds` for `path` to exist (a checkpoint appears by a rename, so it is complete
// when it exists); false if the child ended or time ran out first.
inline bool wait_for_file(const std::filesystem::path& path, ChildProcess& child, double seconds) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (!std::filesystem::exists(path)) {
        if (child.finished() || std::chrono::steady_clock::now() > deadline) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return true;
}

}  // namespace paloverde::test
