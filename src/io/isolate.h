#pragma once
// Running a parser we do not own in a child process, so that its bugs cannot take the program down.
//
// Assimp 5.2.5 (Debian 12's) has heap overflows on malformed files that later Assimp releases fixed (OBJ lines and
// faces, PLY, OFF counts, …): under the fuzzer one of them corrupted the heap so that a later, unrelated free
// aborted. No check of ours before Assimp can cover every such bug, so load_mesh runs Assimp in a forked child:
// a crash, an abort, a hang or a runaway allocation there ends the child, and the parent turns it into one line
// naming the file. The child sends back only plain bytes (its result, serialised by the caller) through a pipe.
#include "core/error.h"

#include <functional>
#include <string>

namespace ff::io {

/// How an isolated call ends.
struct IsolateOptions {
  double timeout_s = 600.0;  ///< the child is killed after this long (a hang in the parser), > 0
};

/// Runs `work` in a forked child and returns the bytes it produced. In the child, fatal signals are reset to their
/// defaults (so a crash ends the child quietly, without the parent's handlers) and it leaves with _exit (no atexit
/// handlers, no leak check). Errors: Input when the child dies by a signal, exits without a whole answer, or runs
/// past `options.timeout_s` (`what` names the work in the message, e.g. "Assimp's import of bunny.obj"); Io when no
/// child can be started (fork or pipe failing). `work` itself must not throw (catch inside and encode the failure
/// in the bytes). Thread-safe in the sense fork() is: the child runs only `work`, which must not wait on locks that
/// other threads of the parent may hold (memory allocation is safe with glibc).
Result<std::string> run_isolated(const std::function<std::string()>& work, const std::string& what,
                                 const IsolateOptions& options = {});

}  // namespace ff::io
