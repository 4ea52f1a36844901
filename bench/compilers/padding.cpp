// WLX_PADDING_BYTES of code that nothing calls, linked before the generated kernels so that their
// code lies at another offset in the program: main.cpp's --variant times each compiler's kernels in
// several such layouts, since the layout alone moved a kernel's time by up to 1.4x.
#define WLX_PADDING_TEXT(bytes) #bytes
#define WLX_PADDING_SIZE(bytes) WLX_PADDING_TEXT(bytes)
__asm__(".text\n.globl wlx_kernels_padding\nwlx_kernels_padding:\n.skip " WLX_PADDING_SIZE(WLX_PADDING_BYTES) ", 0xcc\n");
