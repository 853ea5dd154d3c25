// The per-run HDF5 result file: time series, matrices, attributes and particle snapshots, with an XDMF
// sidecar so ParaView opens the snapshots. HDF5 types stay in run_file.cpp.
//
// Layout written by the solver (group paths are the caller's; this class does not impose them):
//   /gauges/<name>/{time, elevation}   /probes/<name>/{time, velocity (n x D)}
//   /loads/<name>/{time, force (n x D)} /diagnostics/{time, mass, kinetic, ...}
//   /snapshots/<00000>/{xyz (n x 3), <scalar> (n), <vector> (n x 3)} with attribute `time`
//   /debris_frames/<00000>/corners (bodies x 8 x 3) with attribute `time`: the debris boxes for ParaView
// The full reference of the solver's file is docs/results.md.
//
// Crash safety: everything goes to `<path>.part`; finalize() closes it and renames it to `<path>`, so a
// `result.h5` that exists is a run that ended (its `status` attribute says how: ok, unstable or killed). A
// process killed outright leaves only the `.part` file, readable as of its last flush() (nothing is written
// between flushes but what the caller writes then: see solver/run.cpp's cadence, docs/reliability.md).
// Not thread-safe (the serial HDF5 library is not): use one RunFile from one thread.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace flume::h5 {

// One named per-particle field of a snapshot: `data` holds n floats (scalar) or n x 3 floats (vector).
struct Field {
  std::string name;
  const float* data = nullptr;
};

class RunFile {
 public:
  // Creates (truncating) `<path>.part`. Throws std::runtime_error naming the file when it cannot.
  explicit RunFile(std::string path);
  // A resumed run: reopens the `<path>.part` a stopped run left and keeps its snapshots taken before
  // `keep_snapshots_before` (the checkpoint's time); everything else in it is dropped, to be written again.
  // Without a `.part` file it starts a new one, as the constructor above (kept_snapshots() then says 0).
  RunFile(std::string path, double keep_snapshots_before);
  // Closes the `.part` file without renaming it: a run that did not reach finalize() is not a result.
  ~RunFile();
  RunFile(const RunFile&) = delete;
  RunFile& operator=(const RunFile&) = delete;
  RunFile(RunFile&&) noexcept;
  RunFile& operator=(RunFile&&) noexcept;

  const std::string& path() const;  // the final name
  std::string part_path() const;    // where the data goes until finalize()
  std::string xdmf_path() const;    // the sidecar finalize() writes when there are snapshots
  bool finalized() const;

  // A 1-D float64 dataset `<group_path>/<name>`; groups are created as needed. A dataset of that name
  // must not exist yet (series are written once, at the end of a run or when it stops).
  void write_series(const std::string& group_path, const std::string& name,
                    const std::vector<double>& values);
  // A 2-D float64 dataset of shape (row_major.size() / cols) x cols.
  void write_matrix(const std::string& group_path, const std::string& name,
                    const std::vector<double>& row_major, std::size_t cols);

  // A series that grows while the run goes on: `values` is the whole series so far, and only the rows beyond
  // what the file already holds are written (a chunked dataset, unlimited along the rows). Called at each
  // flush and at the end; the series may not shrink, a matrix's columns may not change.
  void append_series(const std::string& group_path, const std::string& name, const std::vector<double>& values);
  void append_matrix(const std::string& group_path, const std::string& name, const std::vector<double>& row_major,
                     std::size_t cols);

  // Attributes on a group ("/" is the root; the group is created if missing). Setting one again replaces it,
  // so `status` can go from "running" to "complete" or "unstable".
  void set_attribute(const std::string& group_path, const std::string& name, const std::string& value);
  void set_attribute(const std::string& group_path, const std::string& name, const char* value);
  void set_attribute(const std::string& group_path, const std::string& name, double value);
  void set_attribute(const std::string& group_path, const std::string& name, std::int64_t value);
  void set_attribute(const std::string& group_path, const std::string& name, int value) {
    set_attribute(group_path, name, static_cast<std::int64_t>(value));
  }

  // Appends /snapshots/<index, 5 digits>/ with xyz (n x 3), each scalar field (n) and vector field (n x 3),
  // all float32, deflate-compressed when the HDF5 build has it. Returns the snapshot's index.
  std::size_t add_snapshot(double time, std::size_t n, const float* xyz,
                           const std::vector<Field>& scalars = {}, const std::vector<Field>& vectors = {});
  std::size_t snapshot_count() const;
  // The times of the snapshots so far (those kept on a resume included).
  std::vector<double> snapshot_times() const;

  // Rigid boxes for the XDMF sidecar, one frame per call: `corners` holds bodies x 8 x 3 floats, each body's
  // corners in VTK hexahedron order (the -z face counter-clockwise seen from above, then the +z face).
  // Stored as /debris_frames/<index, 5 digits>/corners with attribute `time`.
  void add_box_frame(double time, std::size_t bodies, const float* corners);

  // Pushes buffered data to the `.part` file (it stays `.part`); after it the file opens in any HDF5 reader.
  void flush();
  // Closes the file, writes the XDMF sidecar when there are snapshots, and renames `.part` to the final
  // name. Called once, also when a run stops unstable (with `status` set accordingly).
  void finalize();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A small read-only view of a result file, for tests and tools.
class Reader {
 public:
  explicit Reader(const std::string& file);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  bool exists(const std::string& object_path) const;
  // Any numeric dataset, converted to double and flattened in row-major order.
  std::vector<double> read_vector(const std::string& dataset_path) const;
  std::vector<std::size_t> shape(const std::string& dataset_path) const;
  // Member names of a group, sorted.
  std::vector<std::string> list(const std::string& group_path) const;
  std::string string_attribute(const std::string& object_path, const std::string& name) const;
  double number_attribute(const std::string& object_path, const std::string& name) const;

 private:
  std::string file_;
  std::int64_t id_ = -1;  // hid_t
};

// One-shot convenience around Reader.
std::vector<double> read_vector(const std::string& file, const std::string& dataset_path);

}  // namespace flume::h5
