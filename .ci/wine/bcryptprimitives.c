/* ProcessPrng, which Rust's standard library calls for random bytes
 * (HashMap keys) and which Wine 8's bcryptprimitives.dll lacks: the same
 * bytes from RtlGenRandom (advapi32's SystemFunction036). Built with
 * mingw-w64 for the Windows tests under Wine only (.ci/windows.sh); never
 * shipped. */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length)
{
    while (length > 0) {
        ULONG chunk = length > 0x10000000 ? 0x10000000 : (ULONG)length;
        if (!SystemFunction036(data, chunk))
            return FALSE;
        data += chunk;
        length -= chunk;
    }
    return TRUE;
}
