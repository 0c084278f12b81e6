/* Wine 8 (Debian 12) has no ProcessPrng in bcryptprimitives.dll; Rust's std
 * for Windows imports it (Windows 10 and later have it), so a Rust .exe
 * exits 53 under that Wine before main. This stand-in, built as
 * bcryptprimitives.dll and put beside the .exe for the Wine runs only
 * (scripts/windows.sh), fills the buffer from RtlGenRandom
 * (advapi32's SystemFunction036), which Wine has. Never shipped. */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length)
{
    while (length > 0) {
        ULONG chunk = length > 0x40000000 ? 0x40000000 : (ULONG)length;
        if (!SystemFunction036(data, chunk))
            return FALSE;
        data += chunk;
        length -= chunk;
    }
    return TRUE;
}
