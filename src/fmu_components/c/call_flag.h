/*
 * One call at a time on an instance, as FMI 2.0 requires of hosts, enforced for both
 * flavours' binaries: a flag claimed with one atomic compare-and-swap when a call starts and
 * released when it ends. A call that finds the flag claimed (a second thread calling the
 * same instance, or the host's logger calling back from inside a call) is refused and
 * touches nothing. A second thread is told why each time; a logger calling back is told
 * once per running call, so that it cannot recurse without end.
 */
#ifndef CALL_FLAG_H
#define CALL_FLAG_H

#if defined(_MSC_VER)
#include <intrin.h>
typedef volatile long CallFlag;
#define FLAG_SWAP(flag, from, to) (_InterlockedCompareExchange((flag), (to), (from)) == (from))
#define FLAG_STORE(flag, to) ((void)_InterlockedExchange((flag), (to)))
#elif defined(__GNUC__) || defined(__clang__)
typedef long CallFlag;
static inline int flag_swap(CallFlag *flag, long from, long to) {
    return __atomic_compare_exchange_n(flag, &from, to, 0, __ATOMIC_ACQUIRE, __ATOMIC_RELAXED);
}
#define FLAG_SWAP(flag, from, to) flag_swap((flag), (from), (to))
#define FLAG_STORE(flag, to) __atomic_store_n((flag), (to), __ATOMIC_RELEASE)
#else
#include <stdatomic.h>
typedef atomic_long CallFlag;
static inline int flag_swap(CallFlag *flag, long from, long to) {
    return atomic_compare_exchange_strong(flag, &from, to);
}
#define FLAG_SWAP(flag, from, to) flag_swap((flag), (from), (to))
#define FLAG_STORE(flag, to) atomic_store((flag), (to))
#endif

/* The flag's values: free; claimed; claimed, and a logger calling back has been told. */
enum { CALL_FREE = 0, CALL_BUSY = 1, CALL_BUSY_REFUSAL_TOLD = 2 };

/* 1 when this call now has the instance to itself. */
static inline int call_claim(CallFlag *flag) { return FLAG_SWAP(flag, CALL_FREE, CALL_BUSY); }

/* For a call that did not get the instance: 1 if it should log why. `calling_back`: this
   thread is inside the host's logger (host_log_overlap says which). */
static inline int call_refusal_told(CallFlag *flag, int calling_back) {
    return !calling_back || FLAG_SWAP(flag, CALL_BUSY, CALL_BUSY_REFUSAL_TOLD);
}

static inline void call_release(CallFlag *flag) { FLAG_STORE(flag, CALL_FREE); }

#define CALL_OVERLAP_MESSAGE                                                                \
    "%s refused: another call on this instance has not returned (a second thread, or "     \
    "the logger calling back into the instance); FMI allows one call at a time per "       \
    "instance"

#endif
