#pragma once
// Outputs that appear complete or not at all. A writer fills `<final>.tmp-<pid>`,
// checks that every byte reached the disk (closing is where a full disk shows), and
// only then renames it onto the final name; on any error the temporary is removed
// and the final name is untouched. Temporaries left by a killed process are removed
// by the next writer of the same file.
#include <string>

namespace lb {

class AtomicOutput {
public:
    /// Also removes `<final>.tmp-<pid>` files of processes that no longer run.
    explicit AtomicOutput(std::string final_path);
    ~AtomicOutput();
    AtomicOutput(const AtomicOutput&) = delete;
    AtomicOutput& operator=(const AtomicOutput&) = delete;
    const std::string& temp_path() const { return m_temp; }
    const std::string& final_path() const { return m_final; }
    /// Rename the (closed, checked) temporary onto the final name.
    void commit();

private:
    std::string m_final;
    std::string m_temp;
    bool m_committed = false;
};

/// Remove `<path>.tmp-<pid>` files whose process no longer runs (a kill -9 during a
/// write); returns how many were removed. Temporaries of live processes are kept.
int remove_stale_temporaries(const std::string& path);

/// Why a file cannot be created at `path` ("directory 'd' does not exist", "'d' is not a
/// directory", "directory 'd' is not writable", "'p' is a directory"), or "" if nothing
/// is evidently wrong. Commands check their outputs with it before doing any work.
std::string output_path_problem(const std::string& path);
/// output_path_problem, or the C library's reason (errno) when that finds nothing.
std::string create_failure_reason(const std::string& path);
/// IoError naming `what` (e.g. "-o") and the problem, if output_path_problem finds one.
void check_output_path(const std::string& path, const std::string& what);

/// Write `text` to `path` atomically, creating the parent directory. IoError naming
/// the file if it cannot be created, written or renamed (a full disk, a read-only or
/// missing directory, a parent that is a file).
void write_text_atomically(const std::string& path, const std::string& text);

/// Copy `from` to `to` atomically (a temporary renamed onto `to`), creating the parent
/// directory; IoError naming both files on failure, `to` untouched.
void copy_file_atomically(const std::string& from, const std::string& to);

} // namespace lb
