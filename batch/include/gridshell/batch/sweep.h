// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell sweep`: many designs from a manifest, each row one `gridshell run` into its own
// folder, on this machine (N worker processes) or as a Slurm job array (docs/deploy.md).
//
// The sweep folder DIR:
//   sweep.json              the rows as validated (id, options as given, the mesh resolved)
//   rows/<id>/              a row that ran to an exit code: the files of `gridshell run`,
//                           run.log (its output) and status.json; complete or absent
//   rows/.tmp/<id>.<n>/     attempt n of a row while it runs (left behind by a killed attempt)
//   slurm/                  sbatch scripts, the rows of each submission, task logs and claims
//   summary.csv|json|svg    `gridshell sweep collect`
//
// A row is finished when its status is ok (exit 0), invalid (2) or infeasible (3): running it
// again would give the same answer. Failed rows (1: internal error, daemon unreachable) and rows
// without a folder (never run, killed, cancelled) run again when the sweep is started again.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gridshell/batch/remote_options.h"
#include "gridshell/foundation/progress.h"

namespace gridshell::sweep {

// Manifest -------------------------------------------------------------------------------------

/// One design of the manifest.
struct Row {
  std::string id;
  int line = 0;  ///< line of the manifest where the row starts (1-based)
  /// Column -> value as written (empty values left out: the option's default), manifest order;
  /// includes "mesh".
  std::vector<std::pair<std::string, std::string>> values;
  std::string mesh;  ///< the mesh resolved: an absolute path, or example:NAME
  /// `gridshell run` arguments of the row: MESH, then --option value for each value.
  std::vector<std::string> run_arguments() const;
  const std::string* value(const std::string& column) const;
};

struct Manifest {
  std::string path;                  ///< absolute
  std::vector<std::string> columns;  ///< id, mesh and the options, in the manifest's order
  std::vector<Row> rows;
};

/// A problem with one row (or the header: id empty): the column and the reason.
struct Problem {
  int line = 0;
  std::string id;
  std::string column;
  std::string message;
  std::string describe() const;  ///< "line 4 (id r3), column alpha: ..."
};

/// Reads a CSV (header row, RFC 4180 quoting) or JSON Lines manifest (by extension .csv /
/// .jsonl / .ndjson, else by content). Mesh paths are relative to the manifest's folder. Syntax
/// errors throw InvalidInput naming the manifest and the line.
Manifest read_manifest(const std::string& path);

/// How a row's values are checked: the columns a row may set besides id and mesh, and the check
/// of one row. The CLI's checker (sweep_check.cpp) knows `gridshell run`'s flags, which come
/// from the options description, and checks a row as `gridshell run` does before its work.
class RowChecker {
 public:
  virtual ~RowChecker() = default;
  /// The option columns, without "id" and "mesh".
  virtual std::vector<std::string> columns() = 0;
  /// The problems of one row (its mesh is set): (column, message) pairs, none if it is fine.
  virtual std::vector<std::pair<std::string, std::string>> check(const Row& row) = 0;
};

/// Every problem of every row, found without running anything: ids (present, unique, usable as
/// folder names), columns (`checker`'s), and each row's values by `checker`.
std::vector<Problem> validate(const Manifest& manifest, RowChecker& checker);

// Rows on disk ---------------------------------------------------------------------------------

/// The outcome of one row (status.json).
struct RowStatus {
  std::string id;
  /// ok | invalid | infeasible | unconverged | failed | cancelled | killed | pending
  std::string status;
  int exit_code = -1;
  std::string error;  ///< the row's `error:` line, without the prefix
  int attempt = 0;
  std::string host, engine, slurm_job;
  std::string started, finished;  ///< ISO 8601 UTC
  double seconds = 0;
  std::vector<std::pair<std::string, std::string>> options;  ///< the row's values
  /// Results of a row that ran (status ok): alpha_bar, members, crossings, rms_without_notches,
  /// rms_with_notches, max_bending_stress, t_grid, t1, t2 (missing when not computed).
  std::map<std::string, double> results;
  bool finished_for_good() const {
    return status == "ok" || status == "invalid" || status == "infeasible" ||
           status == "unconverged";  // the same row would stop the same way again
  }
};

/// "ok", "invalid", ... for an exit code of `gridshell run` (signals: 128 + n = "killed").
std::string status_of_exit_code(int exit_code);

std::string to_json(const RowStatus& status);
/// Parses status.json; nullopt when the file is missing or unreadable.
std::optional<RowStatus> read_status(const std::string& path);

/// The folder of row `id` in sweep folder `dir`.
std::string row_dir(const std::string& dir, const std::string& id);

/// How rows run.
struct RowSettings {
  std::string gridshell;  ///< the gridshell executable (absolute)
  int threads = 1;        ///< --threads of each run (in-process kernel threads)
  /// Remote options passed to each run (--server, --tls, --tls-ca, --token-file, --timeout).
  RemoteOptions remote;
  std::string engine = "local";
  std::string slurm_job;  ///< JOBID_TASK of the array task running the row
};

/// Runs row `row` of sweep `dir` (`gridshell run` in a child process writing into
/// rows/.tmp/<id>.<attempt>, with status.json and run.log), then moves the folder to rows/<id>
/// in one rename when the run ended with an exit code. A run killed by a signal or cancelled
/// (`cancel` set: the child gets SIGTERM) leaves only its temporary folder. Returns the status.
RowStatus run_row(const std::string& dir, const Row& row, const RowSettings& settings,
                  const std::atomic<bool>* cancel);

/// Output of a command run to its end (run_command).
struct CommandOutput {
  int exit_code = -1;  ///< 128 + n when killed by signal n, 127 when it could not be started
  std::string out, err;
};
/// Runs `argv` (argv[0] looked up in PATH) with no standard input, collecting its output.
CommandOutput run_command(const std::vector<std::string>& argv);

/// The current time as ISO 8601 UTC with milliseconds.
std::string now_iso8601();

// The sweep ------------------------------------------------------------------------------------

/// sweep.json: the validated rows (the sweep's own copy of the manifest).
void write_sweep_file(const std::string& dir, const Manifest& manifest);
/// Reads DIR/sweep.json; throws InvalidInput naming DIR when it is not a sweep folder.
Manifest read_sweep_file(const std::string& dir);

/// The status of every row of the sweep (pending for rows without a folder; a row whose last
/// attempt was interrupted says so in `error`).
std::vector<RowStatus> row_statuses(const std::string& dir, const Manifest& manifest);

/// Writes summary.csv, summary.json and summary.svg into DIR from the rows' status.json files.
/// Returns the statuses.
std::vector<RowStatus> collect(const std::string& dir);

/// The plot of summary.svg: RMS with notches against each swept parameter, the best rows marked.
std::string summary_svg(const Manifest& manifest, const std::vector<RowStatus>& statuses);

/// Holds DIR/.lock (flock) for the life of the object: one submitting sweep per folder.
class FolderLock {
 public:
  explicit FolderLock(const std::string& dir);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

// Engines --------------------------------------------------------------------------------------

struct EngineOptions {
  RowSettings row;
  int workers = 0;     ///< local: concurrent rows (0 = cores)
  int retries = 2;     ///< failed or killed rows are run again up to this many times
  bool quiet = false;  ///< no notes on stdout (the Slurm job id is printed with no_wait anyway)
  /// The caller's progress line (the engines draw the rows' count on it) and cancellation flag
  /// (the CLI's SIGINT/SIGTERM); default: none.
  Progress progress;
  /// Called when an engine is done with the progress line (the CLI ends it); may be empty.
  std::function<void()> end_progress;
  // Slurm
  std::string partition, time, mem;
  int max_parallel = 0;   ///< %K of --array (0 = no limit)
  int rows_per_task = 1;  ///< rows of one array task (it then helps with the others' rows)
  std::vector<std::string> sbatch_args;
  bool no_wait = false;
  double poll_seconds = 2;
};

/// Runs the pending rows on N local worker processes; returns the number of rows left
/// unfinished (failed or interrupted after the retries).
int run_local(const std::string& dir, const Manifest& manifest, const EngineOptions& options);

/// Submits the pending rows as Slurm job arrays and (unless no_wait) waits, resubmitting the rows
/// of failed or killed tasks up to `retries` times. Returns the rows left unfinished (0 with
/// no_wait).
int run_slurm(const std::string& dir, const Manifest& manifest, const EngineOptions& options);

/// One array task (`gridshell sweep task DIR --submission S --task K`): runs its own rows of
/// submission S, then any row of S that no task has claimed yet. Exit code 0 when every row it
/// ran finished, 1 otherwise. `cancel` (the CLI's SIGTERM flag, which Slurm sends on scancel)
/// stops it between rows and cancels the row that runs.
int run_task(const std::string& dir, int submission, int task, const std::atomic<bool>* cancel);

}  // namespace gridshell::sweep
