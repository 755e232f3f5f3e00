/*
 * Forced in (gcc -include) when the linux64 binaries are built, so that they load on glibc
 * 2.17 and later (RHEL/CentOS 7, Rocky 8 and the like). A binary linked on a newer glibc
 * asks for the newest version of each symbol: exp, log and pow at GLIBC_2.29 (their new
 * error handling), dlopen and the pthread keys at GLIBC_2.34 (moved into libc). Each is
 * bound here to the version x86-64 glibc has had since 2.2.5, which computes the same
 * numbers on the same glibc (the same implementation behind a compatibility wrapper), so
 * the results are unchanged. The guard also links libdl and libpthread, where those
 * symbols live on a glibc before 2.34. tests/test_glibc_floor.py checks every symbol.
 */
#if defined(__linux__) && defined(__x86_64__)
__asm__(".symver exp,exp@GLIBC_2.2.5");
__asm__(".symver exp2,exp2@GLIBC_2.2.5");
__asm__(".symver log,log@GLIBC_2.2.5");
__asm__(".symver log2,log2@GLIBC_2.2.5");
__asm__(".symver pow,pow@GLIBC_2.2.5");
__asm__(".symver dlopen,dlopen@GLIBC_2.2.5");
__asm__(".symver dlsym,dlsym@GLIBC_2.2.5");
__asm__(".symver dlerror,dlerror@GLIBC_2.2.5");
__asm__(".symver dladdr,dladdr@GLIBC_2.2.5");
__asm__(".symver dlclose,dlclose@GLIBC_2.2.5");
__asm__(".symver pthread_once,pthread_once@GLIBC_2.2.5");
__asm__(".symver pthread_key_create,pthread_key_create@GLIBC_2.2.5");
__asm__(".symver pthread_key_delete,pthread_key_delete@GLIBC_2.2.5");
__asm__(".symver pthread_setspecific,pthread_setspecific@GLIBC_2.2.5");
__asm__(".symver pthread_getspecific,pthread_getspecific@GLIBC_2.2.5");
#endif
