// Sanitizer defaults for the OpenNI2 tests. OpenNI2 2.2 leaks by design: every device-connected
// event allocates a Device wrapper that is never freed, and initialize() / Device::open() keep
// driver allocations past shutdown (drivers are dlclose()d with them). None of it is ours, so
// LeakSanitizer is told to ignore stacks through OpenNI2 and its drivers; full unwinding lets it
// see those frames (OpenNI2 is built without frame pointers). No effect without a sanitizer.
extern "C" {
// NOLINTNEXTLINE: names fixed by the sanitizer runtime
const char* __asan_default_options();
const char* __lsan_default_suppressions();

const char* __asan_default_options() { return "fast_unwind_on_malloc=0"; }
const char* __lsan_default_suppressions() {
  return "leak:libOpenNI2.so\n"
         "leak:libOniFile.so\n"
         "leak:libPS1080.so\n"
         "leak:libPSLink.so\n"
         "leak:libDummyDevice.so\n"
         "leak:_dl_open\n"
#ifdef HANDTRACK_LSAN_THREADS_ARE_OPENNI2S
         // Threads of drivers already dlclose()d show only unknown frames above start_thread.
         // Set only for tests whose code under test starts no thread of its own (oni: playback).
         "leak:start_thread\n"
#endif
      ;
}
}
