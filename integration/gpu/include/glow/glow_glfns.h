/*
 * glow_glfns.h — the OpenGL 4.5 core entry points Glow's GL code uses, loaded through a host loader
 * (eglGetProcAddress, OSMesaGetProcAddress, glfwGetProcAddress: glow_glctx_get_proc_address gives one).
 * Part of glow_glfns (target glow::glfns, folder integration/gpu/).
 *
 * Why a table and not libGL/libOpenGL: middleware must work in whatever context the host made (EGL on a
 * GPU, OSMesa in CI, GLX through GLFW), and only the context's own GetProcAddress is valid for all of
 * them (GLVND's libOpenGL dispatches only for EGL/GLX contexts, not OSMesa). Debian has no maintained
 * loader that handles OSMesa (libepoxy does not), so this is the small X-macro table such loaders
 * generate, limited to what Glow and its samples call.
 *
 * USAGE
 *   glow_glfns gl; char missing[128];
 *   if (!glow_glfns_load(&gl, glow_glctx_get_proc_address(ctx), missing, sizeof missing)) fail(missing);
 *   gl.CreateBuffers(1, &buf);
 */
#ifndef GLOW_GLOW_GLFNS_H
#define GLOW_GLOW_GLFNS_H

#include <stddef.h>
#include <GL/glcorearb.h>

#include "glow/glow_gl_loader.h"

#ifndef GLOW_API /* as in glow.h: exported from a shared build, nothing for consumers */
#if defined(GLOW_BUILDING_SHARED) && defined(__GNUC__)
#define GLOW_API __attribute__((visibility("default")))
#else
#define GLOW_API
#endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* X(type, name): the function gl<name>, of pointer type <type> (glcorearb.h). */
#define GLOW_GLFNS_LIST(X) \
    X(PFNGLGETERRORPROC, GetError) \
    X(PFNGLGETSTRINGPROC, GetString) \
    X(PFNGLGETSTRINGIPROC, GetStringi) \
    X(PFNGLGETINTEGERVPROC, GetIntegerv) \
    X(PFNGLGETINTEGER64VPROC, GetInteger64v) \
    X(PFNGLGETFLOATVPROC, GetFloatv) \
    X(PFNGLENABLEPROC, Enable) \
    X(PFNGLDISABLEPROC, Disable) \
    X(PFNGLISENABLEDPROC, IsEnabled) \
    X(PFNGLVIEWPORTPROC, Viewport) \
    X(PFNGLCLEARPROC, Clear) \
    X(PFNGLCLEARCOLORPROC, ClearColor) \
    X(PFNGLCLEARDEPTHPROC, ClearDepth) \
    X(PFNGLDEPTHFUNCPROC, DepthFunc) \
    X(PFNGLDEPTHMASKPROC, DepthMask) \
    X(PFNGLCULLFACEPROC, CullFace) \
    X(PFNGLFRONTFACEPROC, FrontFace) \
    X(PFNGLPOLYGONOFFSETPROC, PolygonOffset) \
    X(PFNGLCOLORMASKPROC, ColorMask) \
    X(PFNGLFINISHPROC, Finish) \
    X(PFNGLFLUSHPROC, Flush) \
    X(PFNGLPIXELSTOREIPROC, PixelStorei) \
    X(PFNGLREADPIXELSPROC, ReadPixels) \
    X(PFNGLCREATEBUFFERSPROC, CreateBuffers) \
    X(PFNGLDELETEBUFFERSPROC, DeleteBuffers) \
    X(PFNGLNAMEDBUFFERSTORAGEPROC, NamedBufferStorage) \
    X(PFNGLNAMEDBUFFERDATAPROC, NamedBufferData) \
    X(PFNGLNAMEDBUFFERSUBDATAPROC, NamedBufferSubData) \
    X(PFNGLGETNAMEDBUFFERSUBDATAPROC, GetNamedBufferSubData) \
    X(PFNGLMAPNAMEDBUFFERRANGEPROC, MapNamedBufferRange) \
    X(PFNGLUNMAPNAMEDBUFFERPROC, UnmapNamedBuffer) \
    X(PFNGLCLEARNAMEDBUFFERDATAPROC, ClearNamedBufferData) \
    X(PFNGLCLEARNAMEDBUFFERSUBDATAPROC, ClearNamedBufferSubData) \
    X(PFNGLCOPYNAMEDBUFFERSUBDATAPROC, CopyNamedBufferSubData) \
    X(PFNGLBINDBUFFERPROC, BindBuffer) \
    X(PFNGLBINDBUFFERBASEPROC, BindBufferBase) \
    X(PFNGLBINDBUFFERRANGEPROC, BindBufferRange) \
    X(PFNGLCREATETEXTURESPROC, CreateTextures) \
    X(PFNGLDELETETEXTURESPROC, DeleteTextures) \
    X(PFNGLTEXTURESTORAGE2DPROC, TextureStorage2D) \
    X(PFNGLTEXTURESTORAGE3DPROC, TextureStorage3D) \
    X(PFNGLTEXTURESUBIMAGE2DPROC, TextureSubImage2D) \
    X(PFNGLTEXTURESUBIMAGE3DPROC, TextureSubImage3D) \
    X(PFNGLTEXTUREPARAMETERIPROC, TextureParameteri) \
    X(PFNGLTEXTUREPARAMETERFPROC, TextureParameterf) \
    X(PFNGLTEXTUREPARAMETERFVPROC, TextureParameterfv) \
    X(PFNGLBINDTEXTUREUNITPROC, BindTextureUnit) \
    X(PFNGLBINDIMAGETEXTUREPROC, BindImageTexture) \
    X(PFNGLGETTEXTUREIMAGEPROC, GetTextureImage) \
    X(PFNGLGETTEXTURELEVELPARAMETERIVPROC, GetTextureLevelParameteriv) \
    X(PFNGLGETPROGRAMRESOURCEINDEXPROC, GetProgramResourceIndex) \
    X(PFNGLGETTEXTURESUBIMAGEPROC, GetTextureSubImage) \
    X(PFNGLCLEARTEXIMAGEPROC, ClearTexImage) \
    X(PFNGLGENERATETEXTUREMIPMAPPROC, GenerateTextureMipmap) \
    X(PFNGLCREATESAMPLERSPROC, CreateSamplers) \
    X(PFNGLDELETESAMPLERSPROC, DeleteSamplers) \
    X(PFNGLSAMPLERPARAMETERIPROC, SamplerParameteri) \
    X(PFNGLBINDSAMPLERPROC, BindSampler) \
    X(PFNGLCREATEFRAMEBUFFERSPROC, CreateFramebuffers) \
    X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers) \
    X(PFNGLNAMEDFRAMEBUFFERTEXTUREPROC, NamedFramebufferTexture) \
    X(PFNGLNAMEDFRAMEBUFFERTEXTURELAYERPROC, NamedFramebufferTextureLayer) \
    X(PFNGLNAMEDFRAMEBUFFERDRAWBUFFERPROC, NamedFramebufferDrawBuffer) \
    X(PFNGLNAMEDFRAMEBUFFERDRAWBUFFERSPROC, NamedFramebufferDrawBuffers) \
    X(PFNGLNAMEDFRAMEBUFFERREADBUFFERPROC, NamedFramebufferReadBuffer) \
    X(PFNGLCHECKNAMEDFRAMEBUFFERSTATUSPROC, CheckNamedFramebufferStatus) \
    X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer) \
    X(PFNGLBLITNAMEDFRAMEBUFFERPROC, BlitNamedFramebuffer) \
    X(PFNGLCLEARNAMEDFRAMEBUFFERFVPROC, ClearNamedFramebufferfv) \
    X(PFNGLCREATERENDERBUFFERSPROC, CreateRenderbuffers) \
    X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers) \
    X(PFNGLNAMEDRENDERBUFFERSTORAGEPROC, NamedRenderbufferStorage) \
    X(PFNGLNAMEDFRAMEBUFFERRENDERBUFFERPROC, NamedFramebufferRenderbuffer) \
    X(PFNGLCREATESHADERPROC, CreateShader) \
    X(PFNGLDELETESHADERPROC, DeleteShader) \
    X(PFNGLSHADERSOURCEPROC, ShaderSource) \
    X(PFNGLCOMPILESHADERPROC, CompileShader) \
    X(PFNGLGETSHADERIVPROC, GetShaderiv) \
    X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog) \
    X(PFNGLCREATEPROGRAMPROC, CreateProgram) \
    X(PFNGLDELETEPROGRAMPROC, DeleteProgram) \
    X(PFNGLATTACHSHADERPROC, AttachShader) \
    X(PFNGLDETACHSHADERPROC, DetachShader) \
    X(PFNGLLINKPROGRAMPROC, LinkProgram) \
    X(PFNGLGETPROGRAMIVPROC, GetProgramiv) \
    X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog) \
    X(PFNGLUSEPROGRAMPROC, UseProgram) \
    X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation) \
    X(PFNGLUNIFORM1IPROC, Uniform1i) \
    X(PFNGLUNIFORM1UIPROC, Uniform1ui) \
    X(PFNGLUNIFORM1FPROC, Uniform1f) \
    X(PFNGLUNIFORM2FPROC, Uniform2f) \
    X(PFNGLUNIFORM3FPROC, Uniform3f) \
    X(PFNGLUNIFORM4FPROC, Uniform4f) \
    X(PFNGLUNIFORM3FVPROC, Uniform3fv) \
    X(PFNGLUNIFORM4FVPROC, Uniform4fv) \
    X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv) \
    X(PFNGLUNIFORM2UIPROC, Uniform2ui) \
    X(PFNGLUNIFORM3UIPROC, Uniform3ui) \
    X(PFNGLUNIFORM2IPROC, Uniform2i) \
    X(PFNGLUNIFORM3IPROC, Uniform3i) \
    X(PFNGLPROGRAMUNIFORM1IPROC, ProgramUniform1i) \
    X(PFNGLPROGRAMUNIFORM1UIPROC, ProgramUniform1ui) \
    X(PFNGLPROGRAMUNIFORM1FPROC, ProgramUniform1f) \
    X(PFNGLPROGRAMUNIFORM2UIPROC, ProgramUniform2ui) \
    X(PFNGLPROGRAMUNIFORM3FPROC, ProgramUniform3f) \
    X(PFNGLPROGRAMUNIFORM3FVPROC, ProgramUniform3fv) \
    X(PFNGLPROGRAMUNIFORM4FVPROC, ProgramUniform4fv) \
    X(PFNGLPROGRAMUNIFORMMATRIX4FVPROC, ProgramUniformMatrix4fv) \
    X(PFNGLDISPATCHCOMPUTEPROC, DispatchCompute) \
    X(PFNGLDISPATCHCOMPUTEINDIRECTPROC, DispatchComputeIndirect) \
    X(PFNGLMEMORYBARRIERPROC, MemoryBarrier) \
    X(PFNGLCREATEVERTEXARRAYSPROC, CreateVertexArrays) \
    X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays) \
    X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray) \
    X(PFNGLVERTEXARRAYVERTEXBUFFERPROC, VertexArrayVertexBuffer) \
    X(PFNGLVERTEXARRAYELEMENTBUFFERPROC, VertexArrayElementBuffer) \
    X(PFNGLENABLEVERTEXARRAYATTRIBPROC, EnableVertexArrayAttrib) \
    X(PFNGLVERTEXARRAYATTRIBFORMATPROC, VertexArrayAttribFormat) \
    X(PFNGLVERTEXARRAYATTRIBIFORMATPROC, VertexArrayAttribIFormat) \
    X(PFNGLVERTEXARRAYATTRIBBINDINGPROC, VertexArrayAttribBinding) \
    X(PFNGLDRAWARRAYSPROC, DrawArrays) \
    X(PFNGLDRAWELEMENTSPROC, DrawElements) \
    X(PFNGLDRAWARRAYSINSTANCEDPROC, DrawArraysInstanced) \
    X(PFNGLPOINTSIZEPROC, PointSize) \
    X(PFNGLLINEWIDTHPROC, LineWidth) \
    X(PFNGLBLENDFUNCPROC, BlendFunc) \
    X(PFNGLCREATEQUERIESPROC, CreateQueries) \
    X(PFNGLDELETEQUERIESPROC, DeleteQueries) \
    X(PFNGLQUERYCOUNTERPROC, QueryCounter) \
    X(PFNGLGETQUERYOBJECTUI64VPROC, GetQueryObjectui64v) \
    X(PFNGLGETQUERYOBJECTIVPROC, GetQueryObjectiv) \
    X(PFNGLBEGINQUERYPROC, BeginQuery) \
    X(PFNGLENDQUERYPROC, EndQuery) \
    X(PFNGLFENCESYNCPROC, FenceSync) \
    X(PFNGLDELETESYNCPROC, DeleteSync) \
    X(PFNGLCLIENTWAITSYNCPROC, ClientWaitSync) \
    X(PFNGLDEBUGMESSAGECALLBACKPROC, DebugMessageCallback) \
    X(PFNGLDEBUGMESSAGECONTROLPROC, DebugMessageControl) \
    X(PFNGLOBJECTLABELPROC, ObjectLabel)

typedef struct glow_glfns {
#define GLOW__GLFN_FIELD(type, name) type name;
    GLOW_GLFNS_LIST(GLOW__GLFN_FIELD)
#undef GLOW__GLFN_FIELD
} glow_glfns;

/** Loads every entry point of the list. \returns 1 when all were found; else 0 with the names of the
 * first missing ones in `missing` (may be NULL). Entry points are per context on some platforms:
 * load once per context. */
GLOW_API int glow_glfns_load(glow_glfns *fns, glow_gl_loader load, char *missing, size_t missing_size);

#ifdef __cplusplus
}
#endif
#endif /* GLOW_GLOW_GLFNS_H */
