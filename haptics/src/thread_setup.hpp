#pragma once
// Operating-system settings for the calling thread (private to the haptics library).

namespace hysim::haptics::detail {

// Names the calling thread (shown by top -H, gdb, perf); names are cut to 15 characters.
void nameThisThread(const char* name);

// Asks for SCHED_FIFO at `priority`. When the system refuses (usual without CAP_SYS_NICE or
// an rtprio limit) it writes one line to stderr, once per process, and returns false: the
// loop still runs, only with more jitter.
bool tryRealtimePriority(int priority);

}  // namespace hysim::haptics::detail
