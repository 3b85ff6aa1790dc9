// ThreadSanitizer builds only (USV_FDI_SANITIZER=thread): pthread_mutex_clocklock for TSan.
//
// libfastrtps 2.9 (Debian bookworm) locks its TimedMutex / RecursiveTimedMutex with
// pthread_mutex_clocklock (glibc >= 2.30), which GCC 12's libtsan does not intercept: TSan then
// sees every unlock of those mutexes without the lock ("unlock of an unlocked mutex") and,
// worse, none of the happens-before edges they create. This shared library is linked into our
// TSan executables ahead of libc, so Fast DDS's calls land here and go on to
// pthread_mutex_timedlock, which libtsan does intercept: TSan sees the locks, and no
// suppression is needed for them. Never built into a normal (release) binary.
#include <pthread.h>
#include <time.h>

extern "C" int pthread_mutex_clocklock(pthread_mutex_t* mutex, clockid_t clock,
                                       const struct timespec* abstime) {
  struct timespec deadline = *abstime;
  if (clock != CLOCK_REALTIME) {
    // The same deadline on CLOCK_REALTIME (timedlock's clock).
    struct timespec now_clock, now_real;
    clock_gettime(clock, &now_clock);
    clock_gettime(CLOCK_REALTIME, &now_real);
    const long long left =
        (static_cast<long long>(abstime->tv_sec) - now_clock.tv_sec) * 1000000000LL +
        (abstime->tv_nsec - now_clock.tv_nsec);
    const long long at = static_cast<long long>(now_real.tv_sec) * 1000000000LL + now_real.tv_nsec +
                         (left > 0 ? left : 0);
    deadline.tv_sec = static_cast<time_t>(at / 1000000000LL);
    deadline.tv_nsec = static_cast<long>(at % 1000000000LL);
  }
  return pthread_mutex_timedlock(mutex, &deadline);
}
